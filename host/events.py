"""The daemon's events: one typed value per thing it saw, thought or did.

Everything the daemon learns or does is one of these frozen dataclasses, emitted once on its
event stream (``host.daemon.stream``); the journal, the web page's status, the terminal's
lines and any other reader are projections of that stream; the present state every view shows
is folded once, by ``host.fold.EventFold``.
``Observation`` is a change of one observed literal (``value`` True, False, or None when it
became unknown or expired); ``DiagnosisRecord`` the minimal diagnoses (their bad sets) of one
diagnoser run that changed them, with what triggered it; ``DiagnosisRun`` the cost of every run
(for the metrics; not journaled); ``PlanRecord`` a repair plan's steps; ``ActionRecord`` one
state of one repair action (``started`` first, then ``succeeded``, ``failed`` or ``timeout``
under the same ``action_id``); ``RepairEnded`` how a repair ended; ``QuarantineChange`` and
``HoldChange`` a component taken out of (or given back to) automatic repair, by the daemon or a
person; ``BoardEvent`` what the board said (a trip, a state change, a fresh state after
connecting); ``LinkChange`` the board link going up or down; ``ChannelSample`` the channels'
states and currents and the board's input voltage a few times a second (for the page and the
ROS 2 reports; not journaled); ``JournalHealth`` whether the journal can write and what it
holds in memory until it can (not journaled); ``LoopLag`` the daemon falling behind (its event
loop running late) and catching up (not journaled); ``Telemetry`` a
downsampled summary of the channel currents over one period (never raw samples; stored as
compact ``[channel, samples, mean, min, max, last]`` rows in mA); ``RunStarted`` the start of
one daemon run (its id numbers the journal's runs); ``Note`` free text.

The mission's layers (paper 001; ``host.layers``) add theirs, enough to replay the history of a
mission (``host.plandiag`` reads it): ``MissionState`` the mission started, planned (its temporal
plan, each step with its start and duration), replanned, completed, failed or stopped, and why;
``Dispatch`` one mission action about to be dispatched, with the knowledge base before it, each
start and over-all condition checked against it, and whether it was dispatched or refused;
``TreeChange`` a node of the action's behaviour tree changing status (its tick trace);
``LayerResult`` the result ⟨s, Δ⟩ of a command at any layer above 0 (a skill, a tree, a mission
action with the knowledge base after it), with its start and end; ``KbChange`` atoms added to or
removed from the knowledge base, by an action's start or end effects, by sensing (an observation
overriding the knowledge base) or by the goal reasoner. Every event has a
``kind`` and serialises to plain JSON (``to_json``) and back (``event_from_json``), so the
journal file can be read by anything that reads SQLite + JSON and a history can be replayed
entry by entry; ``describe()`` is its one line for a person.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from enum import StrEnum
from typing import Any, ClassVar

from host.layers import Cause

JSON = dict[str, Any]


class Kind(StrEnum):
    OBSERVATION = "observation"
    DIAGNOSIS = "diagnosis"
    PLAN = "plan"
    ACTION = "action"
    BOARD_EVENT = "board_event"
    TELEMETRY = "telemetry"
    NOTE = "note"
    LINK = "link"
    REPAIR = "repair"
    QUARANTINE = "quarantine"
    HOLD = "hold"
    RUN = "run"
    MISSION = "mission"
    DISPATCH = "dispatch"
    TREE = "tree"
    RESULT = "result"
    KB = "kb"
    PLAN_DIAGNOSIS = "plan_diagnosis"
    # not journaled (for live readers only)
    DIAGNOSIS_RUN = "diagnosis_run"
    CHANNELS = "channels"
    JOURNAL_HEALTH = "journal_health"
    LOOP_LAG = "loop_lag"


class ActionState(StrEnum):
    STARTED = "started"
    SUCCEEDED = "succeeded"
    FAILED = "failed"
    TIMEOUT = "timeout"


# a change of the diagnoser's Observation (host/diagnosis/observations.py) on the event
# stream (scripts/names.py)
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
    # components whose observations expired: unknown, not healthy (host.diagnosis.coverage)
    unknown: tuple[str, ...] = ()
    kind: ClassVar[Kind] = Kind.DIAGNOSIS

    @classmethod
    def of(cls, bad_sets: Sequence[Sequence[str] | frozenset[str]], *, complete: bool = True,
           trigger: str = "", elapsed_s: float = 0.0,
           probabilities: Sequence[float] = (), unknown: Sequence[str] = ()) -> DiagnosisRecord:
        """Build from any bad sets (frozensets, lists): each is sorted, their order kept."""
        return cls(tuple(tuple(sorted(b)) for b in bad_sets), complete, trigger, elapsed_s,
                   tuple(probabilities), tuple(unknown))

    def to_json(self) -> JSON:
        return {"diagnoses": [list(b) for b in self.diagnoses], "complete": self.complete,
                "trigger": self.trigger, "elapsed_s": self.elapsed_s,
                "probabilities": list(self.probabilities), "unknown": list(self.unknown)}

    @classmethod
    def from_json(cls, data: Mapping[str, Any]) -> DiagnosisRecord:
        return cls(tuple(tuple(str(c) for c in b) for b in data["diagnoses"]),
                   bool(data.get("complete", True)), str(data.get("trigger", "")),
                   float(data.get("elapsed_s", 0.0)),
                   tuple(float(p) for p in data.get("probabilities", ())),
                   tuple(str(c) for c in data.get("unknown", ())))


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


# the board client's BoardEvent (host/board/types.py) on the event stream (scripts/names.py)
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


class _Plain:
    """``to_json``/``from_json`` for events whose fields are plain JSON values."""

    def to_json(self) -> JSON:
        return {f.name: getattr(self, f.name) for f in dataclasses.fields(self)}  # type: ignore[arg-type]

    @classmethod
    def from_json(cls, data: Mapping[str, Any]) -> Any:
        names = {f.name for f in dataclasses.fields(cls)}  # type: ignore[arg-type]
        return cls(**{k: v for k, v in data.items() if k in names})


@dataclass(frozen=True)
class LinkChange(_Plain):
    """The board link went up or down (``reason``: why, as the client or the daemon saw it)."""

    up: bool
    reason: str = ""
    # with up: what the board said of this daemon's key ("accepted", "refused: why", "none"
    # when the daemon has no key, "" when the wire cannot tell before a command)
    key: str = ""
    kind: ClassVar[Kind] = Kind.LINK


@dataclass(frozen=True)
class RepairEnded(_Plain):
    """A repair (rounds of diagnose, plan, execute) ended: ``outcome`` as the loop says."""

    outcome: str
    rounds: int
    reason: str = ""
    kind: ClassVar[Kind] = Kind.REPAIR


@dataclass(frozen=True)
class QuarantineChange(_Plain):
    """A component taken out of automatic repair (``quarantined``) or given back.

    ``by`` is ``daemon`` (its attempts ran out) or ``person`` (``dxboard quarantine``);
    ``safe_state`` what was done to leave it safe; ``attempts`` the attempts it had used."""

    component: str
    quarantined: bool
    reason: str = ""
    safe_state: str = ""
    by: str = "daemon"
    attempts: int = 0
    kind: ClassVar[Kind] = Kind.QUARANTINE


@dataclass(frozen=True)
class HoldChange(_Plain):
    """A person told the daemon to leave a component alone (``held``), or released it."""

    component: str
    held: bool
    reason: str = ""
    by: str = "person"
    kind: ClassVar[Kind] = Kind.HOLD


@dataclass(frozen=True)
class RunStarted(_Plain):
    """A daemon run began: every entry after it (until the next) belongs to ``run_id``.

    ``operator`` is its operator socket (for ``dxboard quarantine|hold --operator``), ``healthy``
    the value each observable atom has when nothing is broken, as the model entails it
    (``host.diagnosis.healthy``; atoms the model leaves free are absent)."""

    run_id: str
    robot: str
    board: str = ""
    dry_run: bool = False
    operator: str = ""
    healthy: Mapping[str, bool] = field(default_factory=dict)
    kind: ClassVar[Kind] = Kind.RUN


@dataclass(frozen=True)
class JournalHealth(_Plain):
    """Whether the journal can write: ``problem`` ("" when it writes, else e.g. "disk full"),
    ``held`` the entries it keeps in memory until it can, ``dropped`` those it lost beyond its
    bound (for the page, the API and ``/diagnostics``; not journaled: the journal is what
    fails)."""

    problem: str
    held: int = 0
    dropped: int = 0
    kind: ClassVar[Kind] = Kind.JOURNAL_HEALTH


@dataclass(frozen=True)
class LoopLag(_Plain):
    """How late the daemon's event loop runs (``lag_s``, the worst of the last few seconds) and
    whether that is over the limit it is judged behind at (``behind``): for the page and
    ``/diagnostics`` (not journaled)."""

    lag_s: float
    behind: bool
    limit_s: float = 1.0
    kind: ClassVar[Kind] = Kind.LOOP_LAG


def loop_lag_text(event: LoopLag) -> str:
    """``behind: its event loop runs 2.3 s late`` or ``on time (loop lag 0.01 s)``."""
    if event.behind:
        return f"behind: its event loop runs {event.lag_s:.1f} s late " \
               f"(over {event.limit_s:g} s)"
    return f"on time (loop lag {event.lag_s:.2f} s)"


@dataclass(frozen=True)
class DiagnosisRun(_Plain):
    """One diagnoser run, changed or not: its cost (for the metrics; not journaled)."""

    elapsed_s: float
    trigger: str = ""
    kind: ClassVar[Kind] = Kind.DIAGNOSIS_RUN


@dataclass(frozen=True)
class ChannelReading:
    id: int
    name: str
    on: bool
    state: str
    current_ma: float


@dataclass(frozen=True)
class ChannelSample:
    """Every channel's state and current now, and the board's input voltage (``input_mv``,
    None when unknown) (a few times a second; not journaled)."""

    channels: tuple[ChannelReading, ...]
    input_mv: int | None = None
    kind: ClassVar[Kind] = Kind.CHANNELS

    def to_json(self) -> JSON:
        return {"channels": [dataclasses.asdict(c) for c in self.channels],
                "input_mv": self.input_mv}

    @classmethod
    def from_json(cls, data: Mapping[str, Any]) -> ChannelSample:
        mv = data.get("input_mv")
        return cls(tuple(ChannelReading(**c) for c in data["channels"]),
                   None if mv is None else int(mv))


@dataclass(frozen=True)
class MissionStep:
    """One step of a temporal plan: ⟨a, t_a, d_a⟩ (start and duration in plan seconds)."""

    action: str
    args: tuple[str, ...]
    start: float
    duration: float

    def __str__(self) -> str:
        return f"{self.action}({', '.join(self.args)})"


@dataclass(frozen=True)
class MissionState:
    """The mission's state: ``started``, ``planned`` (``plan``), ``completed``, ``failed`` or
    ``stopped`` (``detail`` says why, naming the components to blame)."""

    mission_id: str
    state: str
    detail: str = ""
    goal: tuple[str, ...] = ()
    plan: tuple[MissionStep, ...] = ()
    components: tuple[str, ...] = ()
    kind: ClassVar[Kind] = Kind.MISSION

    def to_json(self) -> JSON:
        return {"mission_id": self.mission_id, "state": self.state, "detail": self.detail,
                "goal": list(self.goal), "components": list(self.components),
                "plan": [{"action": s.action, "args": list(s.args), "start": s.start,
                          "duration": s.duration} for s in self.plan]}

    @classmethod
    def from_json(cls, data: Mapping[str, Any]) -> MissionState:
        return cls(str(data["mission_id"]), str(data["state"]), str(data.get("detail", "")),
                   tuple(str(g) for g in data.get("goal", ())),
                   tuple(MissionStep(str(s["action"]), tuple(str(a) for a in s["args"]),
                                     float(s["start"]), float(s["duration"]))
                         for s in data.get("plan", ())),
                   tuple(str(c) for c in data.get("components", ())))


@dataclass(frozen=True)
class ConditionCheck:
    """One condition of an action checked against the knowledge base: ``atom`` expected
    ``expected`` (False: a negative condition) ``when`` (``start``, ``over all``, ``end``)."""

    atom: str
    when: str
    expected: bool
    held: bool


@dataclass(frozen=True)
class Dispatch:
    """A mission action about to run: the KB before it (sorted atoms), its start and over-all
    conditions checked against that KB, and whether it was dispatched (``ok``) or refused."""

    dispatch_id: str
    mission_id: str
    step: int
    action: str
    args: tuple[str, ...]
    kb: tuple[str, ...]
    checks: tuple[ConditionCheck, ...]
    ok: bool
    at: float
    kind: ClassVar[Kind] = Kind.DISPATCH

    def to_json(self) -> JSON:
        return {"dispatch_id": self.dispatch_id, "mission_id": self.mission_id,
                "step": self.step, "action": self.action, "args": list(self.args),
                "kb": list(self.kb), "ok": self.ok, "at": self.at,
                "checks": [dataclasses.asdict(c) for c in self.checks]}

    @classmethod
    def from_json(cls, data: Mapping[str, Any]) -> Dispatch:
        return cls(str(data["dispatch_id"]), str(data["mission_id"]), int(data["step"]),
                   str(data["action"]), tuple(str(a) for a in data["args"]),
                   tuple(str(a) for a in data["kb"]),
                   tuple(ConditionCheck(str(c["atom"]), str(c["when"]), bool(c["expected"]),
                                        bool(c["held"])) for c in data["checks"]),
                   bool(data["ok"]), float(data["at"]))

    @property
    def failed_checks(self) -> tuple[ConditionCheck, ...]:
        return tuple(c for c in self.checks if not c.held)


@dataclass(frozen=True)
class TreeChange(_Plain):
    """A node of the behaviour tree refining dispatch ``dispatch_id`` changed status, at tick
    ``tick`` (its trace); ``detail`` is what the node said (a guard's reason to hold)."""

    dispatch_id: str
    node: str
    status: str
    previous: str = ""
    tick: int = 0
    detail: str = ""
    kind: ClassVar[Kind] = Kind.TREE


@dataclass(frozen=True)
class LayerResult:
    """The result ⟨s, Δ⟩ of ``command(args)`` at ``layer`` (1 skill, 2 tree, 3 mission action),
    from ``started`` to ``finished`` (the daemon's clock); for a mission action ``kb`` is the
    knowledge base after it, effects applied and observations sensed."""

    layer: int
    command: str
    args: tuple[str, ...]
    success: bool
    explanation: tuple[Cause, ...]
    started: float
    finished: float
    dispatch_id: str = ""
    kb: tuple[str, ...] = ()
    data: Mapping[str, Any] = field(default_factory=dict)
    kind: ClassVar[Kind] = Kind.RESULT

    def to_json(self) -> JSON:
        return {"layer": self.layer, "command": self.command, "args": list(self.args),
                "success": self.success, "explanation": [c.to_json() for c in self.explanation],
                "started": self.started, "finished": self.finished,
                "dispatch_id": self.dispatch_id, "kb": list(self.kb), "data": dict(self.data)}

    @classmethod
    def from_json(cls, data: Mapping[str, Any]) -> LayerResult:
        return cls(int(data["layer"]), str(data["command"]), tuple(str(a) for a in data["args"]),
                   bool(data["success"]),
                   tuple(Cause.from_json(c) for c in data.get("explanation", ())),
                   float(data["started"]), float(data["finished"]),
                   str(data.get("dispatch_id", "")), tuple(str(a) for a in data.get("kb", ())),
                   dict(data.get("data", {})))


@dataclass(frozen=True)
class KbChange:
    """Atoms added to and removed from the knowledge base; ``source`` is ``effect`` (an
    action's start or end effects), ``sensing`` (an observation overrode the KB), ``goal`` or
    ``init``; ``cause`` says which (``end of navigate(corridor, office, door_office)``)."""

    added: tuple[str, ...]
    removed: tuple[str, ...]
    source: str
    cause: str = ""
    dispatch_id: str = ""
    kind: ClassVar[Kind] = Kind.KB

    def to_json(self) -> JSON:
        return {"added": list(self.added), "removed": list(self.removed), "source": self.source,
                "cause": self.cause, "dispatch_id": self.dispatch_id}

    @classmethod
    def from_json(cls, data: Mapping[str, Any]) -> KbChange:
        return cls(tuple(str(a) for a in data["added"]), tuple(str(a) for a in data["removed"]),
                   str(data["source"]), str(data.get("cause", "")),
                   str(data.get("dispatch_id", "")))


@dataclass(frozen=True)
class PlanDiagnosis(_Plain):
    """The mission layer's plan-execution diagnosis of a failed step (``host.plandiag``): the
    alarm, the classes of the fault, the symptoms, the fault region, the minimal alternative
    histories (one line each, most probable first), the most probable one's winning path
    through the context tree, the knowledge base corrected (``kb``: observed and inferred
    literals, ``~`` for false) or the plan error, and how long it took."""

    mission_id: str
    dispatch_id: str
    step: int
    alarm: str
    classes: list[str]
    symptoms: list[str]
    region: str
    histories: list[str]
    path: list[str]
    kb: list[str]
    plan_error: str
    elapsed_s: float
    kind: ClassVar[Kind] = Kind.PLAN_DIAGNOSIS


Event = (Observation | DiagnosisRecord | PlanRecord | ActionRecord | BoardEvent | Telemetry
         | Note | LinkChange | RepairEnded | QuarantineChange | HoldChange | RunStarted
         | DiagnosisRun | JournalHealth | ChannelSample | MissionState | Dispatch | TreeChange
         | LayerResult | KbChange | PlanDiagnosis | LoopLag)
Payload = Event  # what the journal stores: the journaled events


@dataclass(frozen=True)
class Stamped:
    """One event with the daemon's times: ``wall`` (epoch seconds), ``mono`` (its clock)."""

    wall: float
    mono: float
    event: Event

#: the kinds a journal keeps (the rest are for live readers only)
JOURNALED = frozenset(Kind) - {Kind.DIAGNOSIS_RUN, Kind.CHANNELS, Kind.JOURNAL_HEALTH,
                               Kind.LOOP_LAG}

_DECODERS: dict[Kind, Any] = {
    Kind.OBSERVATION: Observation.from_json,
    Kind.DIAGNOSIS: DiagnosisRecord.from_json,
    Kind.PLAN: PlanRecord.from_json,
    Kind.ACTION: ActionRecord.from_json,
    Kind.BOARD_EVENT: BoardEvent.from_json,
    Kind.TELEMETRY: Telemetry.from_json,
    Kind.NOTE: Note.from_json,
    Kind.LINK: LinkChange.from_json,
    Kind.REPAIR: RepairEnded.from_json,
    Kind.QUARANTINE: QuarantineChange.from_json,
    Kind.HOLD: HoldChange.from_json,
    Kind.RUN: RunStarted.from_json,
    Kind.DIAGNOSIS_RUN: DiagnosisRun.from_json,
    Kind.CHANNELS: ChannelSample.from_json,
    Kind.JOURNAL_HEALTH: JournalHealth.from_json,
    Kind.MISSION: MissionState.from_json,
    Kind.DISPATCH: Dispatch.from_json,
    Kind.TREE: TreeChange.from_json,
    Kind.RESULT: LayerResult.from_json,
    Kind.KB: KbChange.from_json,
    Kind.PLAN_DIAGNOSIS: PlanDiagnosis.from_json,
    Kind.LOOP_LAG: LoopLag.from_json,
}


def event_from_json(kind: Kind | str, data: Mapping[str, Any]) -> Event:
    """Decode a stored event; raises ``ValueError`` for an unknown kind or bad data."""
    try:
        decoded: Event = _DECODERS[Kind(kind)](data)
    except (KeyError, TypeError) as exc:
        raise ValueError(f"bad {kind} entry: {exc!r}") from exc
    return decoded


payload_from_json = event_from_json


def journal_health_text(event: JournalHealth) -> str:
    """``journal: disk full, 12 entries held`` (and the entries lost), or ``journal: writing``."""
    if not event.problem:
        return "journal: writing"
    lost = f", {event.dropped} dropped" if event.dropped else ""
    return f"journal: {event.problem}, {event.held} entries held{lost}"


def _value(v: bool | None) -> str:
    return "unknown" if v is None else ("true" if v else "false")


def describe(event: Event) -> str:
    """One short line for people: the terminal, ``dxboard journal``, the page's journal tail."""
    match event:
        case Observation():
            src = f"  [{event.source}]" if event.source else ""
            return f"{event.literal} = {_value(event.value)}{src}"
        case DiagnosisRecord():
            if not event.diagnoses:
                text = "no diagnosis (observations contradict the model)"
            else:
                healthy = (f"{{}} (unknown: {', '.join(event.unknown)}, whose observations "
                           "expired; healthy where observed)" if event.unknown
                           else "{} (all healthy)")
                text = " | ".join("{" + ", ".join(b) + "}" if b else healthy
                                  for b in event.diagnoses[:4])
                if len(event.diagnoses) > 4:
                    text += f" | ... ({len(event.diagnoses)} in all)"
            extra = "" if event.complete else " (incomplete)"
            trig = f"  [{event.trigger}]" if event.trigger else ""
            return f"{text}{extra}{trig}"
        case PlanRecord():
            steps = "; ".join(f"{s.action}({', '.join(s.args)})" for s in event.steps)
            return f"plan {event.plan_id}: {steps or '(nothing to do)'}"
        case ActionRecord():
            took = ("" if event.finished is None
                    else f" after {event.finished - event.started:.2f} s")
            detail = f": {event.detail}" if event.detail else ""
            return f"{event.action}({', '.join(event.args)}) {event.state.value}{took}{detail}"
        case BoardEvent():
            ch = "" if event.channel is None else f" channel {event.channel}"
            detail = " ".join(f"{k}={v}" for k, v in event.detail.items())
            return f"{event.event}{ch}{'  ' + detail if detail else ''}"
        case Telemetry():
            parts = [f"ch{c.channel} {c.mean_ma:.0f} mA" for c in event.channels]
            return f"{event.period_s:g} s: " + (", ".join(parts) or "(no readings)")
        case Note():
            return event.text if event.level == "info" else f"{event.level}: {event.text}"
        case LinkChange():
            if not event.up:
                return f"board link down: {event.reason}"
            return "board link up" + (f" (the board {event.key} this daemon's key)"
                                      if event.key.startswith("refused") else "")
        case RepairEnded():
            why = f" ({event.reason})" if event.reason else ""
            return f"repair ended: {event.outcome} after {event.rounds} round(s){why}"
        case QuarantineChange(quarantined=True):
            how = ("clear it with `dxboard quarantine clear` to repair it again"
                   if event.by == "daemon" else f"set by {event.by}")
            return (f"quarantined {event.component}: {event.reason}; safe state "
                    f"{event.safe_state or 'as it was'}; {how}")
        case QuarantineChange():
            return f"quarantine of {event.component} cleared by {event.by}"
        case HoldChange(held=True):
            why = f": {event.reason}" if event.reason else ""
            return f"hold on {event.component} by {event.by}{why}: no repair touches it"
        case HoldChange():
            return f"hold on {event.component} released by {event.by}"
        case RunStarted():
            return (f"run {event.run_id}: dxboard run {event.robot}"
                    + (f", board {event.board}" if event.board else "")
                    + (" (dry run)" if event.dry_run else ""))
        case JournalHealth():
            return journal_health_text(event)
        case LoopLag():
            return f"daemon {loop_lag_text(event)}"
        case DiagnosisRun():
            return f"diagnosed in {event.elapsed_s * 1000:.1f} ms [{event.trigger}]"
        case ChannelSample():
            return ", ".join(f"{c.name} {c.state} {c.current_ma:.0f} mA" for c in event.channels)
        case MissionState():
            text = f"mission {event.mission_id} {event.state}"
            if event.plan:
                text += ": " + "; ".join(f"{s.start:g}s {s}" for s in event.plan)
            return text + (f" ({event.detail})" if event.detail else "")
        case Dispatch():
            call = f"{event.action}({', '.join(event.args)})"
            if event.ok:
                return f"dispatch {event.dispatch_id}: {call}"
            bad = ", ".join(("" if c.expected else "not ") + c.atom for c in event.failed_checks)
            return f"dispatch {event.dispatch_id}: {call} refused: {bad} does not hold"
        case TreeChange():
            why = f": {event.detail}" if event.detail else ""
            return f"tree {event.dispatch_id}: {event.node} {event.status}{why}"
        case LayerResult():
            call = f"{event.command}({', '.join(event.args)})"
            how = "succeeded" if event.success else "failed: " + "; because ".join(
                str(c) for c in event.explanation)
            return f"layer {event.layer} {call} {how} after {event.finished - event.started:.1f} s"
        case KbChange():
            parts = [f"+{a}" for a in event.added] + [f"-{a}" for a in event.removed]
            why = f" ({event.cause})" if event.cause else ""
            return f"kb {event.source}: {' '.join(parts) or 'no change'}{why}"
        case PlanDiagnosis():
            what = ", ".join(event.classes) or "nothing explains it"
            best = f": {event.histories[0]}" if event.histories else ""
            return (f"plan diagnosis of {event.dispatch_id or 'step ' + str(event.step)}: "
                    f"{what}{best}" + (f" ({event.plan_error})" if event.plan_error else ""))
    raise TypeError(f"not an event: {event!r}")
