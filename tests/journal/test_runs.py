"""A journal's daemon runs: listed, picked by id, and read one at a time by ``dxboard journal``.

Three runs are written as three daemons would (each opens the file, begins with its
``RunStarted``, numbers its actions from ``a1``), after a stretch written by an older daemon
that gave no run ids.
"""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from host.cli import main
from host.errors import UserError
from host.journal import (
    ActionRecord,
    ActionState,
    Journal,
    JournalReader,
    Note,
    Observation,
    RunStarted,
)
from host.journal.runs import list_runs, new_run_id, pick

T0 = 1_800_000_000.0
IDS = ["20270115T080000-0a0a", "20270115T090000-1b1b", "20270115T100000-2c2c"]


def _run(path: Path, run_id: str | None, start: float, n_actions: int) -> None:
    with Journal(path) as journal:
        def put(payload: object, t: float) -> None:
            journal.record(payload, wall=start + t, mono=start + t)  # type: ignore[arg-type]

        if run_id is not None:
            put(RunStarted(run_id, "tedusar", "tcp://10.0.0.7:7000", run_id == IDS[1]), 0.0)
        put(Note("dxboard run tedusar: board tcp://10.0.0.7:7000"), 0.01)
        for i in range(1, n_actions + 1):
            put(ActionRecord(f"a{i}", "power_up", ("hokuyo",), ActionState.STARTED, start + i),
                float(i))
            put(ActionRecord(f"a{i}", "power_up", ("hokuyo",), ActionState.SUCCEEDED,
                             start + i, start + i + 0.5), i + 0.5)
        put(Note("dxboard run stopped"), n_actions + 1.0)


@pytest.fixture
def journal(tmp_path: Path) -> Path:
    path = tmp_path / "j.sqlite"
    _run(path, None, T0 - 7200, 1)  # an older daemon's (no run id)
    for k, run_id in enumerate(IDS):
        _run(path, run_id, T0 + 3600 * k, 2 + k)
    return path


def test_runs_are_listed_with_their_ids_ranges_and_times(journal: Path) -> None:
    with JournalReader(journal) as reader:
        runs = list_runs(reader)
    assert [r.run_id for r in runs] == ["earlier-1", *IDS]
    assert [r.entries for r in runs] == [4, 7, 9, 11]
    assert [(r.first_id, r.last_id) for r in runs] == [(1, 4), (5, 11), (12, 20), (21, 31)]
    assert runs[1].start_wall == T0 and runs[1].end_wall == T0 + 3.0
    assert runs[2].dry_run and not runs[1].dry_run
    assert runs[3].robot == "tedusar" and runs[3].board == "tcp://10.0.0.7:7000"
    assert runs[0].robot == ""
    assert runs[1].line().startswith(f"{IDS[0]}  ")
    assert "2027-01-15 08:00:00" in runs[1].line() and "#5..#11" in runs[1].line()


def test_pick_takes_an_id_a_unique_prefix_or_the_latest(journal: Path) -> None:
    with JournalReader(journal) as reader:
        runs = list_runs(reader)
    assert pick(runs, None, "j").run_id == IDS[2]
    assert pick(runs, IDS[1], "j").run_id == IDS[1]
    assert pick(runs, "20270115T09", "j").run_id == IDS[1]
    assert pick(runs, "earlier-1", "j").first_id == 1
    with pytest.raises(UserError, match="matches 3 runs"):
        pick(runs, "2027", "j")
    with pytest.raises(UserError, match=f"no run 'x'; its runs: earlier-1, {IDS[0]}"):
        pick(runs, "x", "j")
    with pytest.raises(UserError, match="is empty"):
        pick([], None, "j")


def test_a_journal_of_one_run_only_and_an_empty_one(tmp_path: Path) -> None:
    one = tmp_path / "one.sqlite"
    _run(one, IDS[0], T0, 1)
    with JournalReader(one) as reader:
        assert [r.run_id for r in list_runs(reader)] == [IDS[0]]
    empty = tmp_path / "empty.sqlite"
    Journal(empty).close()
    with JournalReader(empty) as reader:
        assert list_runs(reader) == []
    plain = tmp_path / "plain.sqlite"  # an older daemon's, and not even its start note
    with Journal(plain) as journal:
        journal.record(Observation("on(jaguar)", True, "board"), wall=T0, mono=1.0)
    with JournalReader(plain) as reader:
        assert [(r.run_id, r.entries) for r in list_runs(reader)] == [("earlier-1", 1)]


def test_new_run_ids_say_when_and_differ() -> None:
    ids = {new_run_id(T0) for _ in range(20)}
    assert len(ids) > 15 and all(i.startswith("20270115T080000-") for i in ids)


def test_the_cli_lists_runs_and_shows_one(journal: Path,
                                          capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["journal", str(journal), "--runs"]) == 0
    assert [line.split()[0] for line in capsys.readouterr().out.splitlines()] == [
        "earlier-1", *IDS]
    assert main(["journal", str(journal), "--run", IDS[1][:12], "--tail", "100",
                 "--json"]) == 0
    shown = [json.loads(line) for line in capsys.readouterr().out.splitlines()]
    assert [e["id"] for e in shown] == list(range(12, 21))
    assert shown[0]["kind"] == "run" and shown[0]["data"]["run_id"] == IDS[1]
    assert main(["journal", str(journal), "--run", IDS[0], "--tail", "2"]) == 0
    lines = capsys.readouterr().out.splitlines()
    assert [int(line.split()[0]) for line in lines] == [10, 11]
    assert main(["journal", str(journal), "--run", "nope"]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "no run 'nope'" in err and IDS[2] in err
