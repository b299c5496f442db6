"""A journal holds enough to replay a repair history, and ``dxboard journal`` prints it.

The history is the paper's device-shut-down scenario (paper 000 §VI, figure 6): the jaguar
base loses power, the diagnosis blames it, a plan powers it up, then restarts its driver.
"""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from host.cli import main
from host.journal import (
    ActionRecord,
    ActionState,
    BoardEvent,
    DiagnosisRecord,
    Journal,
    Note,
    Observation,
    PlanRecord,
    PlanStep,
)
from host.journal.summary import Replay, summarize

T0 = 1_800_000_000.0

HISTORY = [
    DiagnosisRecord.of([[]], trigger="start"),
    BoardEvent("state", 7, {"old": "on", "new": "off"}),
    Observation("ok(jaguar_node)", False, "topic:/odom"),
    Observation("on(jaguar)", False, "board"),
    DiagnosisRecord.of([["jaguar", "jaguar_node"]], trigger="observation", elapsed_s=0.004),
    PlanRecord("p1", (PlanStep("power_up", ("jaguar",)),), ("jaguar",)),
    ActionRecord("a1", "power_up", ("jaguar",), ActionState.STARTED, T0 + 6),
    ActionRecord("a1", "power_up", ("jaguar",), ActionState.SUCCEEDED, T0 + 6, T0 + 7.5, "p1"),
    Observation("on(jaguar)", True, "board"),
    DiagnosisRecord.of([["jaguar_node"]], trigger="observation"),
    PlanRecord("p2", (PlanStep("stop_node", ("jaguar_node",)),
                      PlanStep("start_node", ("jaguar_node",))), ("jaguar_node",)),
    ActionRecord("a2", "stop_node", ("jaguar_node",), ActionState.STARTED, T0 + 9),
    ActionRecord("a2", "stop_node", ("jaguar_node",), ActionState.TIMEOUT, T0 + 9, T0 + 14),
    Note("retrying stop_node with SIGKILL", "warning"),
]


def _write(path: Path) -> None:
    with Journal(path) as journal:
        for i, payload in enumerate(HISTORY):
            journal.record(payload, wall=T0 + i, mono=100.0 + i)


def test_replaying_the_journal_rebuilds_what_the_daemon_knew(tmp_path: Path) -> None:
    path = tmp_path / "j.sqlite"
    _write(path)
    with Journal(path) as journal:
        entries = journal.reader.since(0, limit=None)
        midway = Replay.of(e for e in entries if e.id <= 5)
        assert midway.abnormal() == {"jaguar", "jaguar_node"}
        assert midway.observations == {"ok(jaguar_node)": False, "on(jaguar)": False}
        end = Replay.of(entries)
    assert end.abnormal() == {"jaguar_node"}
    assert end.observations["on(jaguar)"] is True
    assert {a: r.state for a, r in end.actions.items()} == {
        "a1": ActionState.SUCCEEDED, "a2": ActionState.TIMEOUT}
    assert [p.plan_id for p in end.plans] == ["p1", "p2"]
    with pytest.raises(ValueError):
        end.apply(entries[0])


def test_summaries_are_one_readable_line() -> None:
    lines = [summarize(p) for p in HISTORY]
    assert lines[0] == "{} (all healthy)  [start]"
    assert lines[4] == "{jaguar, jaguar_node}  [observation]"
    assert lines[7] == "power_up(jaguar) succeeded after 1.50 s"
    assert lines[10] == "plan p2: stop_node(jaguar_node); start_node(jaguar_node)"
    assert lines[13] == "warning: retrying stop_node with SIGKILL"
    assert all("\n" not in line for line in lines)


def test_cli_prints_the_tail_by_kind_and_as_json(tmp_path: Path,
                                                 capsys: pytest.CaptureFixture[str]) -> None:
    path = tmp_path / "j.sqlite"
    _write(path)
    assert main(["journal", str(path), "--tail", "2", "--kind", "action"]) == 0
    out = capsys.readouterr().out.splitlines()
    assert len(out) == 2
    assert "stop_node(jaguar_node) started" in out[0] and "timeout after 5.00 s" in out[1]
    assert out[0].split()[0] == "12"

    assert main(["journal", str(path), "--tail", "3", "--json"]) == 0
    rows = [json.loads(line) for line in capsys.readouterr().out.splitlines()]
    assert [r["id"] for r in rows] == [12, 13, 14]
    assert rows[-1]["kind"] == "note" and rows[-1]["data"]["level"] == "warning"


def test_cli_names_a_bad_file_on_one_line(tmp_path: Path,
                                          capsys: pytest.CaptureFixture[str]) -> None:
    bad = tmp_path / "notes.txt"
    bad.write_text("hello\n" * 500)
    assert main(["journal", str(bad)]) == 2
    err = capsys.readouterr().err.strip()
    assert err.count("\n") == 0 and str(bad) in err and "not a dxboard journal" in err
