"""One event sequence of a run, in the order the daemon emits them: a robot starts healthy, its
laser trips, two power cycles fail, the daemon quarantines it, the link drops and comes back, a
person holds another component, the journal's disk fills and is freed, the quarantine is cleared
by hand and a last repair brings the laser back, an observation expires (unknown), and the loop
runs late once. ``STAMPED`` gives each event the daemon's wall and monotonic times, 1 s apart.
"""

from __future__ import annotations

from host.events import (
    ActionRecord,
    ActionState,
    BoardEvent,
    ChannelReading,
    ChannelSample,
    DiagnosisRecord,
    DiagnosisRun,
    Event,
    HoldChange,
    JournalHealth,
    LinkChange,
    LoopLag,
    Observation,
    PlanRecord,
    PlanStep,
    QuarantineChange,
    RepairEnded,
    RunStarted,
    Stamped,
)

COMPONENTS = ("hokuyo", "hokuyo_node", "jaguar")
WALL0, MONO0 = 1_800_000_000.0, 500.0


def _sample(hokuyo: str = "on", current: float = 310.0) -> ChannelSample:
    return ChannelSample((ChannelReading(0, "sensor_head", True, "on", 120.0),
                          ChannelReading(3, "hokuyo", hokuyo == "on", hokuyo, current),
                          ChannelReading(5, "jaguar", True, "on", 900.0)), input_mv=24100)


def _act(aid: str, action: str, state: ActionState, at: int) -> ActionRecord:
    started = MONO0 + at
    return ActionRecord(aid, action, ("hokuyo",), state, started,
                        None if state is ActionState.STARTED else started + 1.0, "p1")


EVENTS: tuple[Event, ...] = (
    RunStarted("20271129T000000-0f0f", "tedusar", "tcp://127.0.0.1:7000",
               healthy={"tripped(hokuyo)": False, "ok(/scan)": True}),
    LinkChange(True, "connected", "accepted"),
    _sample(),
    Observation("tripped(hokuyo)", False, "board"),
    Observation("ok(/scan)", True, "ros"),
    DiagnosisRun(0.012, "start"),  # the first run is told before what it found
    DiagnosisRecord.of([[]], trigger="start"),
    _sample(),
    BoardEvent("trip", 3),
    _sample("tripped", 0.0),
    Observation("tripped(hokuyo)", True, "board"),
    Observation("ok(/scan)", False, "ros"),
    DiagnosisRun(0.020, "observation"),
    DiagnosisRecord.of([["hokuyo"], ["hokuyo_node"]], trigger="observation",
                       probabilities=[0.9, 0.1]),
    PlanRecord("p1", (PlanStep("power_cycle", ("hokuyo",)),), ("hokuyo",)),
    _act("a1", "power_cycle", ActionState.STARTED, 14),
    _act("a1", "power_cycle", ActionState.FAILED, 14),
    _act("a2", "power_cycle", ActionState.STARTED, 17),
    _act("a2", "power_cycle", ActionState.FAILED, 17),
    RepairEnded("quarantined", 2, "2 attempts failed"),
    QuarantineChange("hokuyo", True, "2 attempts failed", "shutdown(hokuyo)", attempts=2),
    DiagnosisRun(0.018, "safety tick"),
    DiagnosisRecord.of([["hokuyo"]], trigger="safety tick"),
    LinkChange(False, "timeout"),
    LinkChange(True, "reconnected", "accepted"),
    HoldChange("jaguar", True, "new cable", by="person"),
    JournalHealth("disk full", 3),
    JournalHealth(""),
    HoldChange("jaguar", False),
    QuarantineChange("hokuyo", False, by="person"),
    _act("a3", "power_up", ActionState.STARTED, 31),
    _sample(),
    _act("a3", "power_up", ActionState.SUCCEEDED, 31),
    Observation("tripped(hokuyo)", False, "board"),
    Observation("ok(/scan)", True, "ros"),
    DiagnosisRun(0.015, "observation"),
    DiagnosisRecord.of([[]], trigger="observation"),
    Observation("ok(/scan)", None, "expired"),
    DiagnosisRun(0.011, "safety tick"),
    DiagnosisRecord.of([[]], trigger="safety tick", unknown=["hokuyo_node"]),
    Observation("ok(/scan)", True, "ros"),
    DiagnosisRun(0.010, "observation"),
    DiagnosisRecord.of([[]], trigger="observation"),
    LoopLag(2.5, True),
    LoopLag(0.02, False),
)

STAMPED: tuple[Stamped, ...] = tuple(
    Stamped(WALL0 + i, MONO0 + i, e) for i, e in enumerate(EVENTS))
