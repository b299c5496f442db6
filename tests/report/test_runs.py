"""``dxboard report`` draws one daemon run of a journal that holds several.

``make run`` reuses its journal, and every run numbers its actions from ``a1`` again: a report
over the whole file paired the first run's ``a1`` with the last run's, drew one action across
both runs and missed the later recoveries. Here one file holds the device shut-down of paper
000's figure 6 (run ``20270115T080000-aaaa``) and, an hour later, the power-up of figure 5
(run ``20270115T090000-bbbb``); each run's timeline must equal the timeline of a file holding
that run alone, the latest is drawn by default, ``--run`` picks one by id or prefix, and
``--runs`` lists them.
"""

from __future__ import annotations

from pathlib import Path

import pytest

from host.cli import main
from host.journal import Journal, Note, Observation
from host.report.source import load_timeline
from host.report.timeline import Timeline
from tests.report.journals import T0, device_shut_down, power_up

FIRST, SECOND = "20270115T080000-aaaa", "20270115T090000-bbbb"


@pytest.fixture
def two_runs(tmp_path: Path) -> Path:
    path = tmp_path / "two.sqlite"
    device_shut_down(path, run=FIRST)
    power_up(path, run=SECOND, offset=3600.0)
    return path


def _drawn(t: Timeline) -> tuple[object, ...]:
    """What the chart draws (not the file's name or its entry ids), to the microsecond."""
    def r(x: float | None) -> float | None:
        return None if x is None else round(x, 6)

    return (t.robot, t.run, r(t.end), t.clock, t.diagnoses,
            [(w.name, w.group, [(r(i.start), r(i.end), i.state) for i in w.intervals])
             for w in t.rows],
            [(a.action_id, a.label, r(a.start), r(a.end), a.outcome) for a in t.actions],
            [(p.plan_id, r(p.time), p.steps) for p in t.plans],
            [(r(c.abnormal_since), r(c.first_action), r(c.normal_at)) for c in t.recoveries])


def test_each_run_is_drawn_as_if_it_were_alone(two_runs: Path, tmp_path: Path) -> None:
    alone_first = load_timeline(device_shut_down(tmp_path / "a.sqlite", run=FIRST))
    alone_second = load_timeline(power_up(tmp_path / "b.sqlite", run=SECOND))
    latest = load_timeline(two_runs)
    assert _drawn(latest) == _drawn(alone_second)
    assert len(latest.actions) == 11 and latest.end < 45.0
    assert [round(r.repair_s or 0, 1) for r in latest.recoveries] == [30.2]
    first = load_timeline(two_runs, run=FIRST[:12])  # a unique prefix will do
    assert _drawn(first) == _drawn(alone_first)
    assert [a.label for a in first.actions] == [
        "power_up(jaguar)", "stop_node(jaguar_node)", "start_node(jaguar_node)"]
    assert first.first_id == 1 and first.last_id < latest.first_id


def test_the_cli_lists_the_runs_and_draws_the_latest_or_the_one_asked_for(
        two_runs: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["report", str(two_runs), "--runs"]) == 0
    lines = capsys.readouterr().out.splitlines()
    assert [line.split()[0] for line in lines] == [FIRST, SECOND]
    assert "2027-01-15 08:00:00" in lines[0] and "tedusar" in lines[0]
    out = tmp_path / "latest.png"
    assert main(["report", str(two_runs), "-o", str(out)]) == 0
    said = capsys.readouterr().out
    assert f"run {SECOND}" in said and "11 actions" in said and out.stat().st_size > 10_000
    assert main(["report", str(two_runs), "-o", str(out), "--run", FIRST]) == 0
    said = capsys.readouterr().out
    assert f"run {FIRST}" in said and "3 actions" in said


def test_a_run_that_is_not_there_is_one_line_naming_the_runs(
        two_runs: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["report", str(two_runs), "-o", str(tmp_path / "x.png"), "--run", "1999"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and FIRST in err and SECOND in err and "--runs" in err
    assert main(["report", str(two_runs), "-o", str(tmp_path / "x.png"), "--run", "2027"]) == 2
    assert "matches 2 runs" in capsys.readouterr().err
    assert main(["report", str(two_runs)]) == 2  # neither -o nor --runs
    assert "-o FILE.png" in capsys.readouterr().err


def test_journals_from_before_run_ids_are_split_where_each_daemon_started(
        tmp_path: Path) -> None:
    """Older daemons wrote no ``RunStarted``, but noted ``dxboard run ROBOT: board URL``."""
    old = tmp_path / "old.sqlite"
    for offset in (0.0, 3600.0):
        with Journal(old) as journal:
            journal.record(Note("dxboard run tedusar: board tcp://127.0.0.1:7000"),
                           wall=T0 + offset - 1, mono=T0 + offset - 1)
        device_shut_down(old, offset=offset)
    with Journal(old) as journal:
        journal.record(Note("dxboard run stopped"), wall=T0 + 3700, mono=T0 + 3700)
        journal.record(Observation("on(jaguar)", True, "board"), wall=T0 + 3701, mono=T0 + 3701)
    latest = load_timeline(old)
    assert [a.label for a in latest.actions] == [
        "power_up(jaguar)", "stop_node(jaguar_node)", "start_node(jaguar_node)"]
    assert all(a.end is not None and a.end - a.start < 3 for a in latest.actions)
    assert load_timeline(old, run="earlier-1").actions == load_timeline(
        old, run="earlier-2").actions
