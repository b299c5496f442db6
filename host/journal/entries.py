"""The typed entries of the journal: what the daemon records, one frozen dataclass per kind.

Every entry is an ``Entry``: a monotonic ``id`` (assigned by the writer, never reused), the
``wall`` time (seconds since the epoch) and the daemon's ``mono`` time (its monotonic clock,
for durations that a wall-clock step must not distort), both given by the daemon, and a
``payload`` of one of the kinds below. ``Observation`` is a change of one observed literal
(``value`` True, False, or None when it became unknown or expired); ``DiagnosisRecord`` the
minimal diagnoses (their bad sets) of one diagnoser run, with what triggered it;
``PlanRecord`` a repair plan's steps; ``ActionRecord`` one state of one repair action
(``started`` first, then ``succeeded``, ``failed`` or ``timeout`` under the same
``action_id``); ``BoardEvent`` what the board said (link up/down, a trip, a state change);
``Telemetry`` a downsampled summary of the channel currents over one period (never raw
samples; stored as compact ``[channel, samples, mean, min, max, last]`` rows in mA);
``Note`` free text. Payloads serialise to plain JSON (``to_json``) and back
(``payload_from_json``), so the journal file can be read by anything that reads SQLite + JSON
and a history can be replayed entry by entry.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from enum import StrEnum
from typing import Any, ClassVar

JSON = dict[str, Any]


class Kind(StrEnum):
    OBSERVATION = "observation"
    DIAGNOSIS = "diagnosis"
    PLAN = "plan"
    ACTION = "action"
    BOARD_EVENT = "board_event"
    TELEMETRY = "telemetry"
    NOTE = "note"


class ActionState(StrEnum):
    STARTED = "started"
    SUCCEEDED = "succeeded"
    FAILED = "failed"
    TIMEOUT = "timeout"


@dataclass(frozen=True)
class Observation:
    """One observed literal changed: ``value`` True/False, None when unknown or expired."""

    literal: str
    value: bool | None
    source: str = ""
    kind: ClassVar[Kind] = Kind.OBSERVATION

    def to_json(self) -> JSON:
        return {"literal": self.literal, "value": self.value, "source": self.source}

    @classmethod
    def from_json(cls, data: Mapping[str, Any]) -> Observation:
        value = data["value"]
        return cls(str(data["literal"]), None if value is None else bool(value),
                   str(data.get("source", "")))


@dataclass(frozen=True)
class DiagnosisRecord:
    """One diagnoser run: the minimal diagnoses as sorted bad sets, best first."""

    diagnoses: tuple[tuple[str, ...], ...]
    complete: bool = True
    trigger: str = ""
    elapsed_s: float = 0.0
    probabilities: tuple[float, ...] = ()
    kind: ClassVar[Kind] = Kind.DIAGNOSIS

    @classmethod
    def of(cls, bad_sets: Sequence[Sequence[str] | frozenset[str]], *, complete: bool = True,
           trigger: str = "", elapsed_s: float = 0.0,
           probabilities: Sequence[float] = ()) -> DiagnosisRecord:
        """Build from any bad sets (frozensets, lists): each is sorted, their order kept."""
        return cls(tuple(tuple(sorted(b)) for b in bad_sets), complete, trigger, elapsed_s,
                   tuple(probabilities))

    def to_json(self) -> JSON:
        return {"diagnoses": [list(b) for b in self.diagnoses], "complete": self.complete,
                "trigger": self.trigger, "elapsed_s": self.elapsed_s,
                "probabilities": list(self.probabilities)}

    @classmethod
    def from_json(cls, data: Mapping[str, Any]) -> DiagnosisRecord:
        return cls(tuple(tuple(str(c) for c in b) for b in data["diagnoses"]),
                   bool(data.get("complete", True)), str(data.get("trigger", "")),
                   float(data.get("elapsed_s", 0.0)),
                   tuple(float(p) for p in data.get("probabilities", ())))


@dataclass(frozen=True)
class PlanStep:
    action: str
    args: tuple[str, ...] = ()

    def to_json(self) -> JSON:
        return {"action": self.action, "args": list(self.args)}


@dataclass(frozen=True)
class PlanRecord:
    """A repair plan: its steps in order, which diagnosis (bad set) it repairs."""

    plan_id: str
    steps: tuple[PlanStep, ...]
    repairs: tuple[str, ...] = ()
    kind: ClassVar[Kind] = Kind.PLAN

    def to_json(self) -> JSON:
        return {"plan_id": self.plan_id, "steps": [s.to_json() for s in self.steps],
                "repairs": list(self.repairs)}

    @classmethod
    def from_json(cls, data: Mapping[str, Any]) -> PlanRecord:
        steps = tuple(PlanStep(str(s["action"]), tuple(str(a) for a in s.get("args", ())))
                      for s in data["steps"])
        return cls(str(data["plan_id"]), steps, tuple(str(c) for c in data.get("repairs", ())))


@dataclass(frozen=True)
class ActionRecord:
    """One state of one repair action; ``finished`` is None while it runs."""

    action_id: str
    action: str
    args: tuple[str, ...]
    state: ActionState
    started: float
    finished: float | None = None
    plan_id: str = ""
    detail: str = ""
    kind: ClassVar[Kind] = Kind.ACTION

    def to_json(self) -> JSON:
        return {"action_id": self.action_id, "action": self.action, "args": list(self.args),
                "state": self.state.value, "started": self.started, "finished": self.finished,
                "plan_id": self.plan_id, "detail": self.detail}

    @classmethod
    def from_json(cls, data: Mapping[str, Any]) -> ActionRecord:
        finished = data.get("finished")
        return cls(str(data["action_id"]), str(data["action"]),
                   tuple(str(a) for a in data.get("args", ())), ActionState(data["state"]),
                   float(data["started"]), None if finished is None else float(finished),
                   str(data.get("plan_id", "")), str(data.get("detail", "")))


@dataclass(frozen=True)
class BoardEvent:
    """Something the board (or the link to it) did: ``event`` names it, e.g. ``trip``."""

    event: str
    channel: int | None = None
    detail: Mapping[str, Any] = field(default_factory=dict)
    kind: ClassVar[Kind] = Kind.BOARD_EVENT

    def to_json(self) -> JSON:
        return {"event": self.event, "channel": self.channel, "detail": dict(self.detail)}

    @classmethod
    def from_json(cls, data: Mapping[str, Any]) -> BoardEvent:
        channel = data.get("channel")
        return cls(str(data["event"]), None if channel is None else int(channel),
                   dict(data.get("detail", {})))


@dataclass(frozen=True)
class ChannelSummary:
    """One channel's current over one telemetry period, in milliamperes."""

    channel: int
    samples: int
    mean_ma: float
    min_ma: float
    max_ma: float
    last_ma: float


@dataclass(frozen=True)
class Telemetry:
    """Downsampled currents: one summary per channel over ``period_s`` seconds."""

    period_s: float
    channels: tuple[ChannelSummary, ...]
    kind: ClassVar[Kind] = Kind.TELEMETRY

    def to_json(self) -> JSON:
        # compact: a row per channel, currents to 0.1 mA (the stored form is most of the file)
        return {"period_s": self.period_s, "channels": [
            [c.channel, c.samples, round(c.mean_ma, 1), round(c.min_ma, 1), round(c.max_ma, 1),
             round(c.last_ma, 1)] for c in self.channels]}

    @classmethod
    def from_json(cls, data: Mapping[str, Any]) -> Telemetry:
        return cls(float(data["period_s"]), tuple(
            ChannelSummary(int(c[0]), int(c[1]), float(c[2]), float(c[3]), float(c[4]),
                           float(c[5]))
            for c in data["channels"]))


@dataclass(frozen=True)
class Note:
    text: str
    level: str = "info"
    kind: ClassVar[Kind] = Kind.NOTE

    def to_json(self) -> JSON:
        return {"text": self.text, "level": self.level}

    @classmethod
    def from_json(cls, data: Mapping[str, Any]) -> Note:
        return cls(str(data["text"]), str(data.get("level", "info")))


Payload = (Observation | DiagnosisRecord | PlanRecord | ActionRecord | BoardEvent | Telemetry
           | Note)

_DECODERS: dict[Kind, Any] = {
    Kind.OBSERVATION: Observation.from_json,
    Kind.DIAGNOSIS: DiagnosisRecord.from_json,
    Kind.PLAN: PlanRecord.from_json,
    Kind.ACTION: ActionRecord.from_json,
    Kind.BOARD_EVENT: BoardEvent.from_json,
    Kind.TELEMETRY: Telemetry.from_json,
    Kind.NOTE: Note.from_json,
}


def payload_from_json(kind: Kind | str, data: Mapping[str, Any]) -> Payload:
    """Decode a stored payload; raises ``ValueError`` for an unknown kind or bad data."""
    try:
        decoded: Payload = _DECODERS[Kind(kind)](data)
    except (KeyError, TypeError) as exc:
        raise ValueError(f"bad {kind} entry: {exc!r}") from exc
    return decoded


@dataclass(frozen=True)
class Entry:
    """One journal row: id, times given by the daemon, and the typed payload."""

    id: int
    wall: float
    mono: float
    payload: Payload

    @property
    def kind(self) -> Kind:
        return self.payload.kind

    def to_json(self) -> JSON:
        return {"id": self.id, "kind": self.kind.value, "wall": self.wall, "mono": self.mono,
                "data": self.payload.to_json()}
