"""``EventFold``: the daemon's event stream folded once. Only an event that changes it bumps its
version and tells its listeners; a listener that raises is logged and the others still hear;
repair actions keep the order they started in (bounded, or all for an offline reader); what is
out of repair keeps the order it was set in; the first diagnoser run is not a diagnosis; layer 0
as the skills see it reads the fold it is given; the journal's replay folds with it too.
"""

from __future__ import annotations

import logging

import pytest

from host.events import (
    JOURNALED,
    ActionRecord,
    ActionState,
    ChannelSample,
    DiagnosisRecord,
    DiagnosisRun,
    HoldChange,
    MissionState,
    Note,
    Observation,
    QuarantineChange,
    RepairEnded,
    Stamped,
)
from host.fold import EventFold
from host.journal.entries import Entry
from host.journal.summary import Replay
from host.skills import AvailState, Layer0View
from tests.fold.story import STAMPED


def at(i: float, event: object) -> Stamped:
    return Stamped(1000.0 + i, 10.0 + i, event)  # type: ignore[arg-type]


def test_only_a_change_bumps_the_version_and_tells_the_listeners() -> None:
    fold, heard = EventFold(), []
    fold.listeners.append(heard.append)
    assert not fold.feed(at(0, Note("hello")))
    assert (fold.version, fold.updated, heard) == (0, 0.0, [])
    assert fold.feed(at(1, DiagnosisRecord.of([["hokuyo"]])))
    assert (fold.version, fold.updated, [h.event for h in heard]) == (
        1, 1001.0, [DiagnosisRecord.of([["hokuyo"]])])
    assert fold.feed(at(2, MissionState("m1", "started")))  # the mission's events too
    assert fold.mission_seen and fold.mission_status.mission_id == "m1"


def test_a_listener_that_raises_is_logged_and_the_others_still_hear(
        caplog: pytest.LogCaptureFixture) -> None:
    fold, heard = EventFold(), []

    def broken(_: Stamped) -> None:
        raise RuntimeError("a broken view")

    fold.listeners += [broken, heard.append]
    with caplog.at_level(logging.ERROR, logger="host.fold.state"):
        fold(at(0, HoldChange("imu", True, "cable")))
    assert len(heard) == 1 and fold.held == {"imu": "cable"}
    assert "a view of the event fold failed on HoldChange" in caplog.text


def test_repairs_keep_their_order_bounded_and_say_what_is_being_repaired() -> None:
    fold = EventFold(keep_actions=2)

    def act(aid: str, arg: str, state: ActionState) -> ActionRecord:
        return ActionRecord(aid, "power_cycle", (arg,), state, 5.0,
                            None if state is ActionState.STARTED else 6.0)

    fold.feed(at(10, act("a1", "hokuyo", ActionState.STARTED)))
    fold.feed(at(11, act("a2", "jaguar", ActionState.STARTED)))
    assert fold.repairing == {"hokuyo", "jaguar"}
    fold.feed(at(12, act("a1", "hokuyo", ActionState.SUCCEEDED)))  # a known id keeps its place
    assert list(fold.actions) == ["a1", "a2"] and fold.repairing == {"jaguar"}
    a1 = fold.actions["a1"]
    assert (a1.text, a1.started_wall, a1.finished_wall) == ("power_cycle(hokuyo)", 995.0, 996.0)
    fold.feed(at(13, act("a3", "imu", ActionState.STARTED)))
    assert list(fold.actions) == ["a2", "a3"]  # the oldest went
    assert fold.action_of["hokuyo"].state is ActionState.SUCCEEDED
    fold.feed(at(14, RepairEnded("repaired", 1)))
    assert fold.repairing == set() and fold.repairs_by_outcome == {"repaired": 1}
    everything = EventFold(keep_actions=None)
    for i, aid in enumerate("abcdefghijklmnopqrstuvwxyzABCDEFGH"):
        everything.feed(at(i, act(aid, "x", ActionState.STARTED)))
    assert len(everything.actions) == 34


def test_out_of_repair_keeps_the_order_set_and_a_component_set_again_moves_last() -> None:
    fold = EventFold()
    fold.feed(at(0, QuarantineChange("hokuyo", True, "3 attempts", "shutdown(hokuyo)")))
    fold.feed(at(1, HoldChange("hokuyo", True, "maintenance")))  # both: two rows
    fold.feed(at(2, HoldChange("jaguar", True, "", by="board")))
    fold.feed(at(3, QuarantineChange("hokuyo", True, "again")))
    assert [(x.component, x.state) for x in fold.out_of_repair()] == [
        ("hokuyo", "held"), ("jaguar", "held"), ("hokuyo", "quarantined")]
    assert fold.quarantined == {"hokuyo": "again"} and fold.excluded["hokuyo", "held"].since == 1001
    fold.feed(at(4, HoldChange("hokuyo", False)))
    assert fold.held == {"jaguar": ""}


def test_the_first_run_of_the_diagnoser_is_not_yet_a_diagnosis() -> None:
    fold = EventFold()
    fold.feed(at(0, DiagnosisRun(0.01)))
    assert (fold.diagnosed_at, fold.diagnosis_runs) == (0.0, 1)
    fold.feed(at(1, DiagnosisRecord.of([[]])))
    assert fold.diagnosed_at == 1000.0  # the run's time, once it said what it found
    fold.feed(at(2, DiagnosisRun(0.01)))
    assert fold.diagnosed_at == 1002.0


def test_the_recorded_run_ends_with_what_it_says() -> None:
    fold = EventFold()
    for s in STAMPED:
        fold(s)
    assert fold.link_up and fold.best == () and fold.unknown == ()
    assert not fold.out_of_repair() and fold.repairs_by_outcome == {"quarantined": 1}
    assert [a.text for a in fold.actions.values()] == [
        "power_cycle(hokuyo)", "power_cycle(hokuyo)", "power_up(hokuyo)"]
    assert fold.input_v == 24.1 and len(fold.currents_a) == 3


def test_layer0_reads_a_fold_it_is_given_and_folds_nothing_again() -> None:
    fold, heard = EventFold(), []
    view = Layer0View(fold=fold)
    view.listeners.append(lambda: heard.append(view.quarantined))
    view(at(0, QuarantineChange("hokuyo", True, "")))  # the daemon's fold is not its to feed
    assert view.quarantined == {} and heard == []
    fold.feed(at(1, QuarantineChange("hokuyo", True, "")))
    assert heard == [{"hokuyo": "quarantined"}]
    fold.feed(at(2, ChannelSample(())))  # nothing layer 0 says: the skills are not woken
    assert len(heard) == 1
    assert view.availability(["hokuyo"]).state is AvailState.UNAVAILABLE
    view.seed([["jaguar"]], {}, {})  # it missed nothing: a seed changes nothing
    assert view.suspects == set() and not view.diagnosed
    own = Layer0View()  # a view of its own folds what it is called with
    own(at(3, Observation("ok(/scan)", False)))
    own.seed([["jaguar"]], {}, {"imu": ""})
    assert (own.bad_topics, own.suspects, own.held) == ({"/scan"}, {"jaguar"},
                                                        {"imu": "held by person"})


def test_the_journal_replay_folds_with_the_same_fold_and_keeps_every_action_and_change() -> None:
    entries = [Entry(i + 1, s.wall, s.mono, s.event) for i, s in enumerate(STAMPED)
               if s.event.kind in JOURNALED]
    end = Replay.of(entries)
    assert end.fold.version == len(entries)  # every journaled entry changed the one fold
    assert [(a, r.state) for a, r in end.actions.items()] == [
        ("a1", ActionState.FAILED), ("a2", ActionState.FAILED), ("a3", ActionState.SUCCEEDED)]
    midway = Replay.of(e for e in entries if e.wall <= STAMPED[26].wall)  # hokuyo quarantined
    q = midway.quarantined["hokuyo"]
    assert (q.reason, q.safe_state, q.attempts) == ("2 attempts failed", "shutdown(hokuyo)", 2)
    assert midway.held["jaguar"].reason == "new cable" and midway.abnormal() == {"hokuyo"}
    assert not end.quarantined and not end.held
