"""What ``dxboard run`` tells a person on its terminal, and one journal kept by two runs.

Two real ``dxboard run --emulate`` processes on the virtual TEDUSAR robot, one after the other,
with the same journal file (as ``make run`` does it):

1. a daemon as a person starts it: it brings the robot up, then the lidar is hung with
   ``dxboard inject``; it must say so on its terminal, one line at a time, in words a person
   can follow — the diagnosis naming the lidar, the plan, each step's result, and "repair
   ended: healthy" — and nothing of the observation churn underneath;
2. the same with ``-q``: it brings the robot up too (a repair of every device), and prints
   nothing after its URLs.

Then the journal holds two runs, each begun by its own ``RunStarted``: ``dxboard journal
--runs`` and ``dxboard report --runs`` list them, and the report draws the latest run alone (its
actions are its own, none paired with the other run's ``a1``...), or the first with ``--run``.
"""

from __future__ import annotations

import re
import subprocess
import sys
import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import pytest

from host.events import ActionRecord, RunStarted
from host.journal import JournalReader
from host.journal.runs import list_runs
from host.report.source import load_timeline
from tests.daemon.runner import ROOT, RunningDaemon, fast_copy, healthy

HEAL_S = 90.0
STAMP = re.compile(r"^\d\d:\d\d:\d\d ")


@dataclass
class Told:
    """What the two runs printed and served."""

    journal: Path
    loud: list[str]  # terminal lines of the first run, after its URLs
    fault_at: int  # index into ``loud`` of the first line after the fault was injected
    quiet: list[str]  # the same for the -q run
    loud_status: dict[str, Any]
    loud_code: int
    quiet_code: int


def _wait(what: Callable[[], bool], timeout: float, label: str, d: RunningDaemon) -> None:
    end = time.monotonic() + timeout
    while not what():
        if time.monotonic() > end:
            raise AssertionError(f"timed out waiting for {label}; the terminal said:\n"
                                 + "\n".join(d.lines[-40:]))
        time.sleep(0.1)


@pytest.fixture(scope="module")
def told(tmp_path_factory: pytest.TempPathFactory) -> Told:
    tmp = tmp_path_factory.mktemp("terminal")
    robot = fast_copy(tmp)
    loud = RunningDaemon(tmp, robot)
    try:
        status = loud.wait_for(healthy, HEAL_S, "the robot powered up and healthy")
        _wait(lambda: any("repair ended: healthy" in x for x in loud.lines), 30,
              "the power-up's end on the terminal", loud)
        fault_at = len(loud.lines)
        loud.inject("hokuyo", "hang")
        _wait(lambda: any("repair ended: healthy" in x for x in loud.lines[fault_at:]),
              HEAL_S, "the lidar repaired, on the terminal", loud)
    finally:
        loud.close()
    assert loud.proc.returncode is not None
    quiet = RunningDaemon(tmp, robot, extra_args=("-q",))
    try:
        quiet.wait_for(healthy, HEAL_S, "the robot powered up by the quiet daemon")
    finally:
        quiet.close()
    assert quiet.proc.returncode is not None
    return Told(loud.journal_path, list(loud.lines), fault_at, list(quiet.lines), status,
                loud.proc.returncode, quiet.proc.returncode)


def _index(lines: list[str], pattern: str, start: int = 0) -> int:
    for i in range(start, len(lines)):
        if re.search(pattern, lines[i]):
            return i
    raise AssertionError(f"no line matching {pattern!r} in:\n" + "\n".join(lines[start:]))


def test_a_fault_shows_as_lines_a_person_can_follow(told: Told) -> None:
    lines = told.loud
    assert told.loud_code == 0
    assert lines and all(STAMP.match(x) for x in lines), lines
    # first the run's id, for dxboard report --run
    with JournalReader(told.journal) as reader:
        first_run = list_runs(reader)[0].run_id
    assert re.match(rf"^\S+ run {first_run}: dxboard run tedusar, board tcp://", lines[0])
    after = told.fault_at
    diagnosis = _index(lines, r"diagnosis: \{[^}]*\bhokuyo(_node)?\b", after)
    plan = _index(lines, r" plan \S+: .*power_cycle\(hokuyo\)", diagnosis)
    step = _index(lines, r" step: power_cycle\(hokuyo\) succeeded after \d+\.\d\d s", plan)
    ended = _index(lines, r" repair ended: healthy after \d+ round\(s\)", step)
    assert diagnosis < plan < step < ended
    # the start of each step and the observations underneath are left to the journal
    assert not [x for x in lines if re.search(r" step: \S+ started\b", x)
                or re.match(r"^\S+ ~?[\w/]+\([^)]*\) = (true|false|unknown)\b", x)]
    # the power-up before the fault was told the same way
    assert _index(lines, r" step: power_up\(hokuyo\) succeeded") < after


def test_quiet_prints_nothing_after_its_urls(told: Told) -> None:
    assert told.quiet_code == 0
    assert told.quiet == []
    # ... though it did repair: the power-up of its own run is in the journal
    with JournalReader(told.journal) as reader:
        last = list_runs(reader)[-1]
        acts = [e.payload for e in reader.query(after_id=last.after_id, kind="action")]
    assert any(isinstance(a, ActionRecord) and a.action == "power_up" for a in acts)


def test_each_run_has_its_id_and_the_report_draws_one_run(told: Told, tmp_path: Path) -> None:
    with JournalReader(told.journal) as reader:
        runs = list_runs(reader)
        first = reader.query(after_id=runs[0].after_id, to_id=runs[0].first_id)[0].payload
    assert len(runs) == 2 and runs[0].run_id != runs[1].run_id
    assert isinstance(first, RunStarted) and first.robot == "tedusar"
    assert first.healthy["tripped(hokuyo)"] is False and first.healthy["on(hokuyo)"] is True
    # the page's status said the same: its run and which values are healthy
    assert told.loud_status["run_id"] == runs[0].run_id
    assert told.loud_status["healthy"]["tripped(hokuyo)"] is False

    def dxboard(*args: str) -> str:
        out = subprocess.run([sys.executable, "-m", "host.cli", *args], cwd=ROOT, check=True,
                             capture_output=True, text=True, timeout=120)
        return out.stdout

    listed = dxboard("report", str(told.journal), "--runs").splitlines()
    assert [x.split()[0] for x in listed] == [r.run_id for r in runs]
    assert dxboard("journal", str(told.journal), "--runs").splitlines() == listed
    said = dxboard("report", str(told.journal), "-o", str(tmp_path / "latest.png"))
    assert f"run {runs[1].run_id}" in said
    latest = load_timeline(told.journal)
    assert latest.run == runs[1].run_id and latest.actions
    length = runs[1].end_wall - runs[1].start_wall
    for a in latest.actions:  # each paired with its own end, inside its own run
        assert a.end is not None and 0 <= a.start <= a.end <= length + 1, a
    assert {a.label for a in latest.actions} >= {"power_up(hokuyo)", "power_up(jaguar)"}
    first_run = load_timeline(told.journal, run=runs[0].run_id)
    assert "power_cycle(hokuyo)" in {a.label for a in first_run.actions}
    assert "power_cycle(hokuyo)" not in {a.label for a in latest.actions}
