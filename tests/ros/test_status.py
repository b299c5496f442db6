"""`/diagnostics` as a projection of the one fold of the daemon's events (pure, no clock)."""

from __future__ import annotations

from host.events import (
    ActionRecord,
    ActionState,
    BoardEvent,
    ChannelReading,
    ChannelSample,
    DiagnosisRecord,
    JournalHealth,
    LinkChange,
    Note,
    QuarantineChange,
    Stamped,
)
from host.fold import EventFold
from host.ros.status import ERROR, OK, STALE, WARN, Diagnostics


def feed(fold: EventFold, *events: object) -> None:
    for e in events:
        fold.feed(Stamped(0.0, 0.0, e))  # type: ignore[arg-type]


def by_name(view: Diagnostics) -> dict[str, tuple[int, str, dict[str, str]]]:
    return {s.name: (s.level, s.message, dict(s.values)) for s in view.statuses()}


def test_components_follow_the_diagnoses_repairs_and_quarantine() -> None:
    fold = EventFold()
    view = Diagnostics(["hokuyo", "hokuyo_node", "jaguar"], fold)
    assert by_name(view)["dxboard/components/hokuyo"][0] == STALE  # nothing diagnosed yet
    assert not fold.feed(Stamped(0.0, 0.0, Note("hello")))  # changes nothing
    feed(fold, DiagnosisRecord.of([["hokuyo"], ["hokuyo_node"]]))
    s = by_name(view)
    assert s["dxboard/components/hokuyo"][:2] == (ERROR, "abnormal in the best diagnosis {hokuyo}")
    assert s["dxboard/components/hokuyo_node"][:2] == (WARN, "abnormal in 1 of 2 minimal diagnoses")
    assert s["dxboard/components/jaguar"][:2] == (OK, "normal in every minimal diagnosis")
    assert s["dxboard/components/hokuyo"][2]["diagnoses"] == "1 of 2"
    feed(fold, ActionRecord("a1", "power_cycle", ("hokuyo",), ActionState.STARTED, 1.0))
    assert by_name(view)["dxboard/components/hokuyo"][2]["repair"] == "power_cycle(hokuyo) started"
    feed(fold, DiagnosisRecord.of([[]]), QuarantineChange("jaguar", True, "3 attempts"))
    s = by_name(view)
    assert s["dxboard/components/hokuyo"][0] == OK
    assert s["dxboard/components/jaguar"][0] == ERROR
    assert s["dxboard/components/jaguar"][1].endswith("quarantined: 3 attempts")
    assert s["dxboard/components/jaguar"][2]["quarantined"] == "true"


def test_board_and_channels() -> None:
    fold = EventFold()
    view = Diagnostics([], fold)
    assert by_name(view)["dxboard/board/link"][:2] == (ERROR, "link down: not connected yet")
    sample = ChannelSample((ChannelReading(0, "sensor_head", True, "on", 250.0),
                            ChannelReading(3, "hokuyo", False, "tripped", 0.0)))
    feed(fold, LinkChange(True, "connected"), sample, BoardEvent("trip", 3))
    s = by_name(view)
    assert s["dxboard/board/link"][0] == OK
    assert s["dxboard/board/channels/sensor_head"][0] == OK
    assert s["dxboard/board/channels/hokuyo"][:2] == (ERROR, "tripped")
    assert s["dxboard/board/channels/hokuyo"][2]["last_event"] == "trip"
    assert fold.currents_a == [0.25, 0.0]
    assert fold.input_v is None  # the sample did not say the board's input voltage
    feed(fold, ChannelSample(sample.channels, input_mv=22150))
    assert fold.input_v == 22.15
    assert by_name(view)["dxboard/board/link"][2]["input_v"] == "22.150"
    feed(fold, LinkChange(False, "timeout"))
    assert fold.input_v is None  # no longer known
    s = by_name(view)
    assert s["dxboard/board/link"][:2] == (ERROR, "link down: timeout")
    assert s["dxboard/board/channels/sensor_head"][0] == STALE


def test_the_daemon_has_a_status_of_its_own_that_says_a_full_disk() -> None:
    fold = EventFold()
    view = Diagnostics(["hokuyo"], fold)
    assert by_name(view)["dxboard/daemon"][:2] == (OK, "journal: writing")
    assert fold.feed(Stamped(0.0, 0.0, JournalHealth("disk full", 7)))
    level, message, values = by_name(view)["dxboard/daemon"]
    assert (level, message) == (ERROR, "journal: disk full, 7 entries held")
    assert values["journal_held"] == "7"
    feed(fold, JournalHealth(""))
    assert by_name(view)["dxboard/daemon"][:2] == (OK, "journal: writing")


def test_the_diagnosis_and_the_repair_have_statuses_of_their_own() -> None:
    fold = EventFold()
    view = Diagnostics(["hokuyo", "hokuyo_node"], fold)
    s = by_name(view)
    assert s["dxboard/diagnosis"][:2] == (STALE, "not diagnosed yet")
    assert s["dxboard/repair"][:2] == (OK, "no repair yet")
    feed(fold, DiagnosisRecord.of([["hokuyo"], ["hokuyo_node"]]))
    level, message, values = by_name(view)["dxboard/diagnosis"]
    assert (level, message) == (ERROR, "best diagnosis {hokuyo}")
    assert values["diagnoses"] == "2" and values["all"] == "{hokuyo}; {hokuyo_node}"
    feed(fold, ActionRecord("a1", "power_cycle", ("hokuyo",), ActionState.FAILED, 1.0))
    assert by_name(view)["dxboard/repair"][:2] == (ERROR, "power_cycle(hokuyo) failed")
    feed(fold, ActionRecord("a2", "power_cycle", ("hokuyo",), ActionState.SUCCEEDED, 2.0),
         DiagnosisRecord.of([[]]))
    s = by_name(view)
    assert s["dxboard/repair"][:2] == (OK, "power_cycle(hokuyo) succeeded")
    assert s["dxboard/diagnosis"][:2] == (OK, "every component normal")
    feed(fold, DiagnosisRecord.of([[]], unknown=["hokuyo_node"]))
    assert by_name(view)["dxboard/diagnosis"][:2] == (STALE, "unknown: hokuyo_node")


def test_every_status_name_is_a_path_under_dxboard_with_a_hardware_id() -> None:
    fold = EventFold()
    view = Diagnostics(["hokuyo"], fold)
    feed(fold, LinkChange(True, "connected"),
         ChannelSample((ChannelReading(3, "hokuyo", True, "on", 10.0),)))
    statuses = view.statuses()
    assert {s.name for s in statuses} == {
        "dxboard/components/hokuyo", "dxboard/board/link", "dxboard/board/channels/hokuyo",
        "dxboard/diagnosis", "dxboard/repair", "dxboard/daemon"}
    assert all(s.hardware_id for s in statuses)
