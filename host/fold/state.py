"""``EventFold``: the daemon's event stream folded, once, into what every view shows.

``EventFold()`` is a reader of the stream (``daemon.subscribe(fold)``, or ``fold.feed(stamped)``
by hand); each ``Stamped`` event that changes what it holds returns True, bumps ``version``,
sets ``updated`` (the event's wall time) and is passed on to the ``listeners`` (the
projections: the page, ``/diagnostics``), which read the fold and never fold again; a listener
that raises is logged and never stops the others. ``sections`` counts the changes of each part
(``channels``, ``observations``, ``diagnosis``, ``actions``, ...), so that a view rebuilds only
what changed. It holds:

- the run (``RunStarted``), the board link (``LinkChange``: up, why not, what the board said of
  the key), the latest channel sample with a short history of currents per channel and the
  latest board event per channel (``ChannelSample``, ``BoardEvent``);
- the observed literals (``Observation``) and how many changes were seen;
- the latest diagnosis (``DiagnosisRecord``: ``diagnoses``, ``best``, ``suspects``,
  ``unknown``) and the diagnoser's runs (``DiagnosisRun``: when, how long; ``diagnosed_at``
  only once a diagnosis is known, so that no view calls the robot healthy before);
- the repair: the recent actions in the order they started, their times turned into wall time
  with the event's own stamp (``ActionRecord``; ``keep_actions`` of them, None for all), the
  latest action, the components an action works on now (``repairing``: from its start to its
  end, all cleared by ``RepairEnded``), the plans (``PlanRecord``; the last ``keep_plans``) and
  how repairs ended (``RepairEnded``);
- the components out of automatic repair (``QuarantineChange``, ``HoldChange``), as
  ``Exclusion``\\ s in the order they were set;
- the journal's health (``JournalHealth``), the daemon's lag (``LoopLag``) and the mission
  (``host.fold.mission``).

It is pure (no clock, no I/O), on the floor just above ``host.events``, so every view and the
offline readers (the journal's ``Replay``) can use it.
"""

from __future__ import annotations

import logging
from collections import Counter, deque
from collections.abc import Callable
from dataclasses import dataclass, field

from host.events import (
    ActionRecord,
    ActionState,
    BoardEvent,
    ChannelSample,
    DiagnosisRecord,
    DiagnosisRun,
    HoldChange,
    JournalHealth,
    LinkChange,
    LoopLag,
    Observation,
    PlanRecord,
    QuarantineChange,
    RepairEnded,
    RunStarted,
    Stamped,
)
from host.fold.mission import MissionFold, MissionStatus

log = logging.getLogger(__name__)

HISTORY = 120  # currents kept per channel (the page's sparklines)
RECENT_ACTIONS = 30
RECENT_PLANS = 10
QUARANTINED, HELD = "quarantined", "held"


@dataclass(frozen=True)
class Exclusion:
    """A component out of automatic repair (``state``: quarantined or held) since ``since``
    (wall time), why, by whom (daemon, person, board) and, for a quarantine, its safe state;
    ``change`` is the event that set it, whole (a restarted daemon restores it)."""

    component: str
    state: str
    reason: str
    by: str
    since: float
    safe_state: str = ""
    change: QuarantineChange | HoldChange | None = field(default=None, compare=False)


@dataclass(frozen=True)
class RepairAction:
    """The latest record of one repair action, with its start and end in wall time."""

    record: ActionRecord
    started_wall: float | None
    finished_wall: float | None

    @property
    def text(self) -> str:
        """``power_cycle(hokuyo)``: how every view names the action."""
        return f"{self.record.action}({', '.join(self.record.args)})"


class EventFold:
    """The state the daemon's events say, folded once; see the module's docstring."""

    def __init__(self, *, keep_actions: int | None = RECENT_ACTIONS,
                 keep_plans: int | None = RECENT_PLANS) -> None:
        self.keep_actions = keep_actions
        self.run: RunStarted | None = None
        self.link_up = False
        self.link_reason = "not connected yet"
        self.board_key = ""
        self.channels: ChannelSample | None = None
        self.history: dict[str, deque[float]] = {}
        self.last_board_event: dict[int, str] = {}
        self.observations: dict[str, bool | None] = {}
        self.observation_changes = 0
        self.diagnosis: DiagnosisRecord | None = None
        self.last_run_wall = 0.0  # wall time of the diagnoser's last run (0: none yet)
        self.diagnosis_runs = 0
        self.diagnosis_latency_sum_s = 0.0
        self.diagnosis_last_latency_s: float | None = None
        self.actions: dict[str, RepairAction] = {}  # by action id, in the order they started
        self.last_action: ActionRecord | None = None
        self.action_of: dict[str, ActionRecord] = {}  # argument -> the latest action on it
        self.repairing: set[str] = set()
        self.plans: deque[PlanRecord] = deque(maxlen=keep_plans)
        self.repairs_by_outcome: Counter[str] = Counter()
        self.excluded: dict[tuple[str, str], Exclusion] = {}  # (component, state), in order set
        self.journal = JournalHealth("")
        self.lag = LoopLag(0.0, False)
        self.mission = MissionFold()
        self.mission_seen = False  # any event of the mission's yet
        self.updated = 0.0  # wall time of the newest event that changed the fold
        self.version = 0
        self.sections: Counter[str] = Counter()  # section -> its own version (a view's cache)
        self.listeners: list[Callable[[Stamped], None]] = []

    def __call__(self, stamped: Stamped) -> None:
        self.feed(stamped)

    def feed(self, stamped: Stamped) -> bool:
        """Fold one event in; True (and the listeners told) when it changed the fold."""
        section = self._fold(stamped)
        if section is None:
            return False
        self.sections[section] += 1
        self.version += 1
        self.updated = stamped.wall
        for listener in list(self.listeners):
            try:
                listener(stamped)
            except Exception:  # a broken view must not stop the others (nor the stream)
                log.exception("a view of the event fold failed on %s",
                              type(stamped.event).__name__)
        return True

    def _fold(self, stamped: Stamped) -> str | None:
        """Fold ``stamped`` in; the section it changed (``sections``), None when none."""
        e = stamped.event
        match e:
            case ChannelSample():
                self.channels = e
                for c in e.channels:
                    self.history.setdefault(c.name, deque(maxlen=HISTORY)).append(c.current_ma)
                return "channels"
            case Observation():
                self.observations[e.literal] = e.value
                self.observation_changes += 1
                return "observations"
            case DiagnosisRecord():
                self.diagnosis = e
                return "diagnosis"
            case DiagnosisRun():
                self.diagnosis_runs += 1
                self.last_run_wall = stamped.wall
                self.diagnosis_latency_sum_s += e.elapsed_s
                self.diagnosis_last_latency_s = e.elapsed_s
                return "runs"
            case ActionRecord():
                self._action(e, stamped)
                return "actions"
            case PlanRecord():
                self.plans.append(e)
                return "plans"
            case RepairEnded():
                self.repairs_by_outcome[e.outcome] += 1
                self.repairing.clear()
                return "outcomes"
            case LinkChange():
                self.link_up, self.link_reason = e.up, e.reason
                if e.up:
                    self.board_key = e.key
                return "link"
            case RunStarted():
                self.run = e
                return "run"
            case QuarantineChange():
                self._exclude(e, QUARANTINED, e.quarantined, stamped.wall, e.safe_state)
                return "excluded"
            case HoldChange():
                self._exclude(e, HELD, e.held, stamped.wall)
                return "excluded"
            case JournalHealth():
                self.journal = e
                return "journal"
            case LoopLag():
                self.lag = e
                return "lag"
            case BoardEvent() if e.channel is not None:
                self.last_board_event[e.channel] = e.event
                return "board_events"
            case _:
                if self.mission(e) is None:
                    return None
                self.mission_seen = True
                return "mission"

    def _action(self, e: ActionRecord, stamped: Stamped) -> None:
        def wall(mono: float | None) -> float | None:
            return None if mono is None else stamped.wall - (stamped.mono - mono)

        self.last_action = e
        self.action_of.update((arg, e) for arg in e.args)
        self.actions[e.action_id] = RepairAction(e, wall(e.started), wall(e.finished))
        while self.keep_actions is not None and len(self.actions) > self.keep_actions:
            del self.actions[next(iter(self.actions))]  # a known id keeps its place
        if e.state is ActionState.STARTED:
            self.repairing |= set(e.args)
        else:
            self.repairing -= set(e.args)

    def _exclude(self, e: QuarantineChange | HoldChange, state: str, now_set: bool, wall: float,
                 safe_state: str = "") -> None:
        self.excluded.pop((e.component, state), None)  # set again: it moves to the end
        if now_set:
            self.excluded[e.component, state] = Exclusion(e.component, state, e.reason, e.by,
                                                          wall, safe_state, e)

    # --- the facts every view reads, derived here once ---

    @property
    def diagnosed_at(self) -> float:
        """Wall time of the diagnoser's last run, once it said a diagnosis (0: not diagnosed
        yet: its first run is told before the diagnosis it found, and in between nothing is
        known, not "healthy")."""
        return self.last_run_wall if self.diagnosis is not None else 0.0

    @property
    def diagnoses(self) -> tuple[tuple[str, ...], ...]:
        """The latest minimal diagnoses (empty before the first, or when nothing is broken)."""
        return self.diagnosis.diagnoses if self.diagnosis is not None else ()

    @property
    def best(self) -> tuple[str, ...]:
        """The best (first) minimal diagnosis: the components surely to blame first."""
        return self.diagnoses[0] if self.diagnoses else ()

    @property
    def suspects(self) -> set[str]:
        """Every component abnormal in some minimal diagnosis."""
        return {c for bad in self.diagnoses for c in bad}

    @property
    def unknown(self) -> tuple[str, ...]:
        """Components whose observations expired: unknown, not healthy."""
        return self.diagnosis.unknown if self.diagnosis is not None else ()

    def probabilities(self) -> tuple[float | None, ...]:
        """Each diagnosis' probability, in order (None when the diagnoser gave none)."""
        d = self.diagnosis
        if d is None:
            return ()
        if len(d.probabilities) == len(d.diagnoses):
            return tuple(d.probabilities)
        return (None,) * len(d.diagnoses)

    def out_of_repair(self, state: str | None = None) -> tuple[Exclusion, ...]:
        """The components out of automatic repair, in the order set (one ``state`` only)."""
        return tuple(x for x in self.excluded.values() if state is None or x.state == state)

    @property
    def quarantined(self) -> dict[str, str]:
        """Quarantined component -> why."""
        return {x.component: x.reason for x in self.out_of_repair(QUARANTINED)}

    @property
    def held(self) -> dict[str, str]:
        """Held component -> why."""
        return {x.component: x.reason for x in self.out_of_repair(HELD)}

    @property
    def input_v(self) -> float | None:
        """The board's input voltage (V) while the link is up and the board says it."""
        mv = self.channels.input_mv if self.channels is not None else None
        return mv / 1000.0 if mv is not None and self.link_up else None

    @property
    def currents_a(self) -> list[float]:
        """Every channel's current (A), in channel order; empty before the first sample."""
        return [c.current_ma / 1000.0 for c in self.channels.channels] if self.channels else []

    @property
    def mission_status(self) -> MissionStatus:
        return self.mission.status
