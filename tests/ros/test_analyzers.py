"""The package's ``config/analyzers.yaml`` groups every dxboard status into one tree.

diagnostic_aggregator is C++ and not on PyPI, so its matching rule is applied here as its
``GenericAnalyzer::match`` defines it (a status belongs to an analyzer whose ``name`` or
``expected`` equals its name, whose ``startswith`` or ``find_and_remove_prefix`` begins it,
whose ``contains`` is in it, or whose ``regex`` matches it whole), to every status name the
daemon's fold (``host.ros.status``) makes: each must be matched by exactly one analyzer, and
all of them inside the one ``AnalyzerGroup`` at path ``dxboard``.
"""

from __future__ import annotations

import re
from pathlib import Path
from typing import Any

import yaml

from host.events import ChannelReading, ChannelSample, DiagnosisRecord, LinkChange, Stamped
from host.fold import EventFold
from host.ros.status import Diagnostics

ROOT = Path(__file__).resolve().parents[2]
ANALYZERS = ROOT / "ros" / "dxboard_ros" / "config" / "analyzers.yaml"
GENERIC = "diagnostic_aggregator/GenericAnalyzer"
GROUP = "diagnostic_aggregator/AnalyzerGroup"


def generic_analyzers(tree: dict[str, Any], path: str) -> list[tuple[str, dict[str, Any]]]:
    """(full path, parameters) of every GenericAnalyzer under ``tree``, groups walked."""
    out = []
    for key, sub in tree.items():
        if not isinstance(sub, dict) or "type" not in sub:
            continue
        here = f"{path}/{sub['path']}"
        if sub["type"] == GROUP:
            out += generic_analyzers(sub.get("analyzers", {}), here)
        elif sub["type"] == GENERIC:
            out.append((here, sub))
        else:
            raise AssertionError(f"{key}: unknown analyzer type {sub['type']}")
    return out


def matches(params: dict[str, Any], name: str) -> bool:
    return (any(re.fullmatch(r, name) for r in params.get("regex", []))
            or name in params.get("expected", []) or name in params.get("name", [])
            or any(name.startswith(p) for p in [*params.get("startswith", []),
                                                *params.get("find_and_remove_prefix", [])])
            or any(c in name for c in params.get("contains", [])))


def test_every_status_lands_in_one_analyzer_of_the_dxboard_group() -> None:
    params = yaml.safe_load(ANALYZERS.read_text())["analyzers"]["ros__parameters"]
    analyzers = generic_analyzers(params, "/" + params["path"])
    assert analyzers and all(p.startswith("/Robot/dxboard/") for p, _ in analyzers)
    fold = EventFold()
    view = Diagnostics(["hokuyo", "hokuyo_node", "link"], fold)  # a component named like a status
    for event in (LinkChange(True, "up"), DiagnosisRecord.of([["hokuyo"]]),
                  ChannelSample((ChannelReading(0, "hokuyo", True, "on", 1.0),
                                 ChannelReading(1, "link", True, "on", 1.0)))):
        fold.feed(Stamped(0.0, 0.0, event))
    where = {s.name: [p for p, a in analyzers if matches(a, s.name)] for s in view.statuses()}
    assert where == {
        "dxboard/components/hokuyo": ["/Robot/dxboard/components"],
        "dxboard/components/hokuyo_node": ["/Robot/dxboard/components"],
        "dxboard/components/link": ["/Robot/dxboard/components"],
        "dxboard/board/link": ["/Robot/dxboard/board"],
        "dxboard/board/channels/hokuyo": ["/Robot/dxboard/board"],
        "dxboard/board/channels/link": ["/Robot/dxboard/board"],
        "dxboard/diagnosis": ["/Robot/dxboard/daemon"],
        "dxboard/repair": ["/Robot/dxboard/daemon"],
        "dxboard/daemon": ["/Robot/dxboard/daemon"],
    }
