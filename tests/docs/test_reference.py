"""The reference of ``system.yaml`` lists exactly the keys the loaders accept.

Each section of a real robot's ``system.yaml`` (a copy of ``models/tedusar``'s, with one example
entry of every observer kind) is given an unknown key; the real loaders refuse each with "use
one of [...]", naming the keys they accept. Those sets, and no other key, must be in the
reference page ``system.yaml`` (made by ``scripts/gen_docs.py`` as the site builds), so a key
added to a loader without its line in the reference fails here.
"""

from __future__ import annotations

import ast
import re
import shutil
from pathlib import Path
from typing import Any

import pytest
import yaml

from host.diagnosis.model import ModelError, check_system
from host.observers.config import load_observers
from host.repair.processes import load_processes
from tests.docs.blocks import ROOT, gen_docs

system_yaml_keys = gen_docs().system_yaml_keys

UNKNOWN = "zz_not_a_key"
_ONE_OF = re.compile(r"unknown key '" + UNKNOWN + r"'.*\(use one of (\[.*?\])\)")


def documented() -> set[str]:
    return {key for key, _default, _meaning in system_yaml_keys()}


def robot_with_unknown_keys(tmp: Path) -> Path:
    """models/tedusar with UNKNOWN in every mapping of system.yaml (and an entry of every
    observer kind to carry it)."""
    robot = tmp / "robot"
    shutil.copytree(ROOT / "models" / "tedusar", robot)
    data: dict[str, Any] = yaml.safe_load((robot / "system.yaml").read_text())
    data[UNKNOWN] = 1
    for kind, name in (("N", "rviz"), ("HN", "imu_node"), ("SN", "jaguar_node"),
                       ("SH", "jaguar"), ("H", "imu")):
        assert data["components"][name]["kind"] == kind
        data["components"][name][UNKNOWN] = 1
    obs = data["observers"]
    obs[UNKNOWN] = 1
    obs["source"] = {"kind": "zenoh", UNKNOWN: 1}
    obs["hardware"][UNKNOWN] = 1
    obs["nodes"]["jaguar_node"][UNKNOWN] = 1
    obs["topics"]["/odom"][UNKNOWN] = 1
    obs["trends"] = {"odom_yaw_rate": {"topic": "/odom", "key": "twist.angular.z", UNKNOWN: 1}}
    obs["diagnostics"] = {"/odom": [{"key": "k", "max": 1, "literal": "ok(/odom)", UNKNOWN: 1}]}
    obs["properties"] = {"jaguar_node": {"cpu_percent": 90, UNKNOWN: 1}}
    obs["responses"] = [{"input": "/cmd_vel", "output": "/odom", "within": 0.5, UNKNOWN: 1}]
    data["processes"]["jaguar_node"][UNKNOWN] = 1
    data["processes"]["rviz"] = {"systemd": "rviz.service", UNKNOWN: 1}
    (robot / "system.yaml").write_text(yaml.safe_dump(data, sort_keys=False))
    return robot


def accepted(problems: list[str]) -> list[set[str]]:
    """The key sets named by the 'unknown key' problems."""
    return [set(ast.literal_eval(m.group(1))) for p in problems if (m := _ONE_OF.search(p))]


def problems_of(loader: Any, robot: Path) -> list[str]:
    try:
        loader(robot)
    except ModelError as exc:
        return [str(p) for p in exc.problems]
    raise AssertionError(f"{loader.__name__} accepted a key it does not know")


def test_every_key_the_loaders_accept_is_documented_and_no_other(tmp_path: Path) -> None:
    robot = robot_with_unknown_keys(tmp_path)
    model_problems = [str(p) for p in check_system(robot)]
    top, *kinds = accepted(model_problems)
    assert len(kinds) == 5, model_problems
    observer_sets = accepted(problems_of(load_observers, robot))
    assert len(observer_sets) == 9, observer_sets
    process_sets = accepted(problems_of(load_processes, robot))
    assert len(process_sets) == 2, process_sets

    docs = documented()
    leaves = {part.removesuffix("[]") for k in docs for part in k.split(".")}
    code_keys = top | set().union(*kinds) | set().union(*observer_sets) | set().union(
        *process_sets)
    missing = sorted(k for k in code_keys if k not in leaves)
    assert not missing, f"keys the loaders accept, missing in the reference: {missing}"
    # each documented top-level, component and process key is one the code accepts
    assert {k for k in docs if "." not in k} == top
    assert {k.split(".")[2] for k in docs if k.startswith("components.NAME.")} == set().union(
        *kinds)
    assert {k.split(".")[2] for k in docs if k.startswith("processes.NODE.")} == set().union(
        *process_sets)
    obs_documented = {k.rsplit(".", 1)[-1].removesuffix("[]") for k in docs
                      if k.startswith("observers.") and k.count(".") >= 1}
    extra = obs_documented - set().union(*observer_sets) - {
        "NODE", "TOPIC", "VALUE", "responses", "devices"}
    assert extra <= {"nodes", "topics", "trends", "matched", "diagnostics", "properties",
                     "source", "hardware"}, extra


@pytest.mark.parametrize("key", ["observers.topics.TOPIC.silence", "processes.NODE.settle_s",
                                 "observers.hardware.link_timeout", "components.NAME.prior"])
def test_defaults_are_the_codes_constants(key: str) -> None:
    from host.diagnosis.logic import DEFAULT_PRIOR
    from host.observers.hardware import DEFAULT_LINK_TIMEOUT
    from host.observers.topics import DEFAULT_SILENCE
    from host.repair.processes import DEFAULT_SETTLE_S

    want = {"observers.topics.TOPIC.silence": DEFAULT_SILENCE,
            "processes.NODE.settle_s": DEFAULT_SETTLE_S,
            "observers.hardware.link_timeout": DEFAULT_LINK_TIMEOUT,
            "components.NAME.prior": DEFAULT_PRIOR}[key]
    default = dict((k, d) for k, d, _ in system_yaml_keys())[key]
    assert default == f"`{want:g}`"
