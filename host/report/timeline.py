"""The timeline model: a journal's history as rows of normal/abnormal intervals and action spans.

``build_timeline`` folds journal entries, in id order, into what the paper's figures 5 and 6
show (paper 000 §VI): one ``ComponentRow`` per component with the ``Interval``\\ s in which it
was ``normal``, ``abnormal`` or ``unknown``; the repair actions as ``ActionSpan``\\ s (start,
end, outcome); the plans as ``PlanMark``\\ s; every ``Recovery``, the moment the whole
system became normal again after something was abnormal; and, when the journal holds a
mission, its layers' commands (``host.report.mission``) and its plan-execution diagnoses
(``host.report.diagnosis``). The rules:

- A component is **abnormal** from a diagnosis entry whose *first-ranked* diagnosis (bad set)
  names it until the next diagnosis entry that does not; **normal** while a diagnosis exists
  and its first-ranked bad set does not name it (the repair planner repairs the first
  diagnosis, paper 000 §IV-E, so this is what the robot acted on). Before the first diagnosis,
  and while a diagnosis entry lists no diagnosis at all (the observations contradict the
  model), every component is **unknown**.
- An abnormal interval shorter than the repair debounce (``debounce_s``, the daemon's 0.5 s)
  that a later diagnosis took back, with no repair action started in it, is **retracted**: a
  verdict the daemon rightly did not act on (a loaded machine's topic late for a moment), not a
  fault. Nor is the moment it was taken back a recovery.
- An action's span runs from its ``started`` to the ``finished`` of the entry that ended it
  (the same ``action_id``); its outcome is that entry's state (succeeded, failed, timeout), or
  ``running`` if the journal holds no end. Action times are the daemon's own (``started`` and
  ``finished``); they are put on the axis through the entry that carried them, whichever of
  the entry's two clocks (wall or monotonic) they were taken on.
- The entries are one daemon run's (``host.journal.runs``: each run numbers its actions
  afresh, so two runs' ``a1`` are different actions). The time axis is in seconds from the
  start of the run, or of the window when one is chosen (``WindowBound``: seconds on the run's axis,
  or ``#ID`` a journal id). It follows the daemon's monotonic clock, so a wall-clock step
  cannot distort durations, unless that clock goes backwards within the entries (entries of an
  older daemon that wrote no run ids, across a reboot): then it follows wall time.
- Rows are the components that the model lists (when one is given), then every other
  component the journal names: in diagnoses, in component observations (``on(d)``,
  ``in_band(d)``, ``tripped(d)``, ``link(b)`` for hardware, ``running(n)`` for nodes) and as
  arguments of repair actions (``power_up`` & co. for hardware, ``start_node`` & co. for
  nodes). The group of a row (hardware, drivers, nodes) comes from the model's kinds, else
  from those literals and actions, else it is ``other``.

Pure: entries in, a frozen ``Timeline`` out; reading files is ``host.report.source``.
"""

from __future__ import annotations

import itertools
import logging
import re
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from enum import StrEnum

from host.events import (
    ActionRecord,
    ActionState,
    DiagnosisRecord,
    Observation,
    PlanRecord,
)
from host.journal.entries import Entry
from host.report.diagnosis import DiagnosisMark, clip_marks, diagnosis_marks
from host.report.mission import LayerSpan, clip_spans, mission_spans

log = logging.getLogger(__name__)


class HealthState(StrEnum):
    NORMAL = "normal"
    ABNORMAL = "abnormal"
    UNKNOWN = "unknown"
    RETRACTED = "retracted"  # abnormal for less than the debounce, taken back, not repaired


DEBOUNCE_S = 0.5  # the daemon's repair debounce (host.daemon.core's repair_debounce_s)


class Group(StrEnum):
    """Row groups, in the order the chart stacks them (top to bottom)."""

    HARDWARE = "hardware"
    DRIVERS = "drivers"
    NODES = "nodes"
    OTHER = "other"


GROUP_ORDER = (Group.HARDWARE, Group.DRIVERS, Group.NODES, Group.OTHER)

RUNNING = "running"  # the outcome of an action whose end the journal does not hold

# what a literal or an action says about the kind of its argument
_HARDWARE_LITERALS = {"on", "in_band", "tripped", "link"}
_NODE_LITERALS = {"running"}
_HARDWARE_ACTIONS = {"power_up", "shutdown", "power_cycle", "power_down"}
_NODE_ACTIONS = {"start_node", "stop_node", "restart_node", "reconfigure_node"}
_LITERAL = re.compile(r"^~?\s*(\w+)\s*\(\s*([^(),\s]+)\s*\)$")


@dataclass(frozen=True)
class Interval:
    """``state`` from ``start`` to ``end``, in seconds on the timeline's axis."""

    start: float
    end: float
    state: HealthState

    @property
    def duration(self) -> float:
        return self.end - self.start


@dataclass(frozen=True)
class ComponentRow:
    """One component: its group and its intervals, contiguous, in time order."""

    name: str
    group: Group
    intervals: tuple[Interval, ...]

    def state_at(self, t: float) -> HealthState:
        """The state at ``t`` (an interval holds its start, not its end; past the end: last)."""
        for iv in self.intervals:
            if iv.start <= t < iv.end:
                return iv.state
        return self.intervals[-1].state if self.intervals else HealthState.UNKNOWN

    def time_in(self, state: HealthState) -> float:
        return sum(iv.duration for iv in self.intervals if iv.state is state)


@dataclass(frozen=True)
class ActionSpan:
    """One repair action: ``end`` is None while it runs (the chart draws it to the end)."""

    action_id: str
    action: str
    args: tuple[str, ...]
    start: float
    end: float | None
    outcome: str  # an ActionState value other than "started", or RUNNING
    plan_id: str = ""
    detail: str = ""

    @property
    def label(self) -> str:
        return f"{self.action}({', '.join(self.args)})"

    @property
    def ok(self) -> bool:
        return self.outcome == ActionState.SUCCEEDED.value


@dataclass(frozen=True)
class PlanMark:
    """A repair plan was made at ``time``."""

    time: float
    plan_id: str
    steps: tuple[str, ...]


@dataclass(frozen=True)
class Recovery:
    """The whole system became normal at ``normal_at`` after being abnormal since
    ``abnormal_since``; ``first_action`` is the first repair action started in between."""

    abnormal_since: float
    first_action: float | None
    normal_at: float

    @property
    def repair_s(self) -> float | None:
        """Seconds from the first repair action to all normal (the paper's 30.2 s)."""
        return None if self.first_action is None else self.normal_at - self.first_action


@dataclass(frozen=True)
class Timeline:
    """Everything the chart draws. Times are seconds on the axis, ``start`` is 0."""

    name: str
    robot: str
    start: float
    end: float
    origin_wall: float  # wall time (epoch seconds) at t = 0
    first_id: int
    last_id: int
    clock: str  # "mono" or "wall": what the axis follows
    rows: tuple[ComponentRow, ...]
    actions: tuple[ActionSpan, ...]
    plans: tuple[PlanMark, ...]
    recoveries: tuple[Recovery, ...]
    diagnoses: int  # diagnosis entries in the window
    window: str = ""  # how the window was chosen ("" for the whole run)
    run: str = ""  # the daemon run drawn (its run id), "" when not known
    mission: tuple[LayerSpan, ...] = ()  # the mission's layers (host.report.mission)
    plan_diagnoses: tuple[DiagnosisMark, ...] = ()  # host.report.diagnosis

    def row(self, name: str) -> ComponentRow:
        for r in self.rows:
            if r.name == name:
                return r
        raise KeyError(name)


@dataclass(frozen=True)
class WindowBound:
    """One end of a window: seconds on the journal's axis, or a journal id (``#ID``)."""

    value: float
    is_id: bool = False

    @classmethod
    def parse(cls, text: str) -> WindowBound:
        """``12.5`` / ``12.5s`` seconds, ``#120`` / ``id:120`` an id; ``ValueError`` else."""
        t = text.strip()
        for prefix in ("#", "id:"):
            if t.startswith(prefix):
                ident = int(t[len(prefix):])
                if ident < 1:
                    raise ValueError(f"journal ids start at 1, not {ident}")
                return cls(float(ident), True)
        seconds = float(t.removesuffix("s"))
        if seconds != seconds or seconds in (float("inf"), float("-inf")):
            raise ValueError(f"{text!r} is not a finite number of seconds")
        return cls(seconds)

    def __str__(self) -> str:
        return f"#{int(self.value)}" if self.is_id else f"{self.value:g} s"


class EmptyWindow(ValueError):
    """The window holds no time (or the journal no entries)."""


def _axis_clock(entries: Sequence[Entry]) -> str:
    monos = [e.mono for e in entries]
    return "mono" if all(b >= a for a, b in itertools.pairwise(monos)) else "wall"


def _infer_groups(entries: Sequence[Entry]) -> dict[str, Group]:
    """Components the journal names, with the group its literals/actions tell (or OTHER)."""
    found: dict[str, Group] = {}

    def see(name: str, group: Group) -> None:
        if found.get(name, Group.OTHER) is Group.OTHER:
            found[name] = group

    for e in entries:
        p = e.payload
        if isinstance(p, DiagnosisRecord):
            for bad in p.diagnoses:
                for c in bad:
                    see(c, Group.OTHER)
        elif isinstance(p, Observation):
            m = _LITERAL.match(p.literal)
            if m and m.group(1) in _HARDWARE_LITERALS:
                see(m.group(2), Group.HARDWARE)
            elif m and m.group(1) in _NODE_LITERALS:
                see(m.group(2), Group.NODES)
        elif isinstance(p, ActionRecord):
            if p.action in _HARDWARE_ACTIONS:
                for a in p.args:
                    see(a, Group.HARDWARE)
            elif p.action in _NODE_ACTIONS:
                for a in p.args:
                    see(a, Group.NODES)
    return found


def _action_time(value: float, entry: Entry, entry_at: float) -> float:
    """``value`` (on the entry's wall or mono clock, whichever is nearer) on the axis, given
    the entry's own place ``entry_at`` on it."""
    offset = value - (entry.wall if abs(value - entry.wall) <= abs(value - entry.mono)
                      else entry.mono)
    return entry_at + offset


def build_timeline(entries: Sequence[Entry], *, name: str, robot: str = "",
                   groups: Mapping[str, Group] | None = None, start: WindowBound | None = None,
                   end: WindowBound | None = None, run: str = "",
                   debounce_s: float = DEBOUNCE_S) -> Timeline:
    """Fold ``entries`` (one daemon run, ``run``, in id order) into a ``Timeline`` of the
    window.

    ``groups`` is the model's components in its order, with their groups; ``start``/``end``
    bound the window; ``debounce_s`` is the repair debounce (what is retracted within it).
    Raises ``EmptyWindow`` if the window holds no time.
    """
    if not entries:
        raise EmptyWindow("the journal holds no entries")
    clock = _axis_clock(entries)

    def at(e: Entry) -> float:
        return (e.mono - entries[0].mono) if clock == "mono" else (e.wall - entries[0].wall)

    # --- components and their groups -------------------------------------------------------
    inferred = _infer_groups(entries)
    order: dict[str, Group] = dict(groups or {})
    for c in sorted(inferred, key=lambda c: (GROUP_ORDER.index(inferred[c]), c)):
        order.setdefault(c, inferred[c])

    # --- actions (paired by id), plans and the diagnosis changes, on the journal's axis -----
    first_start: dict[str, tuple[ActionRecord, Entry]] = {}
    last_end: dict[str, tuple[ActionRecord, Entry]] = {}
    plans: list[PlanMark] = []
    changes: list[tuple[float, frozenset[str] | None]] = []  # None: no diagnosis
    diag_times: list[float] = []
    for e in entries:
        p = e.payload
        if isinstance(p, ActionRecord):
            first_start.setdefault(p.action_id, (p, e))
            if p.state is not ActionState.STARTED:
                last_end[p.action_id] = (p, e)
        elif isinstance(p, PlanRecord):
            steps = tuple(f"{s.action}({', '.join(s.args)})" for s in p.steps)
            plans.append(PlanMark(at(e), p.plan_id, steps))
        elif isinstance(p, DiagnosisRecord):
            diag_times.append(at(e))
            changes.append((at(e), frozenset(p.diagnoses[0]) if p.diagnoses else None))
    spans: list[ActionSpan] = []
    for aid, (rec, e) in first_start.items():
        t0 = _action_time(rec.started, e, at(e))
        frec, fe = last_end.get(aid, (rec, e))
        if frec.finished is None or frec.state is ActionState.STARTED:
            spans.append(ActionSpan(aid, rec.action, rec.args, t0, None, RUNNING,
                                    rec.plan_id, rec.detail))
            continue
        t1 = _action_time(frec.finished, fe, at(fe))
        spans.append(ActionSpan(aid, rec.action, rec.args, t0, max(t0, t1), frec.state.value,
                                frec.plan_id or rec.plan_id, frec.detail))

    # --- the window -------------------------------------------------------------------------
    def resolve(b: WindowBound, is_start: bool) -> float:
        if not b.is_id:
            return b.value
        ids = [e for e in entries if (e.id >= b.value if is_start else e.id <= b.value)]
        if not ids:
            raise EmptyWindow(f"no journal entry {'at or after' if is_start else 'up to'} "
                              f"id {int(b.value)} (ids {entries[0].id}..{entries[-1].id})")
        return at(ids[0] if is_start else ids[-1])

    last_t = max([at(entries[-1])] + [s.end for s in spans if s.end is not None])
    ws = resolve(start, True) if start is not None else 0.0
    we = resolve(end, False) if end is not None else last_t
    if we <= ws:
        raise EmptyWindow(f"the window {ws:.1f} s .. {we:.1f} s is empty (the journal spans "
                          f"0 .. {last_t:.1f} s, ids {entries[0].id}..{entries[-1].id})")
    inside = [e for e in entries if ws <= at(e) <= we]

    def clip(t: float) -> float:
        return min(max(t, ws), we) - ws

    # --- rows -------------------------------------------------------------------------------
    rows: list[ComponentRow] = []
    for comp, group in order.items():
        rows.append(ComponentRow(comp, group, _intervals(comp, changes, ws, we)))

    # --- recoveries: all normal again after something was abnormal --------------------------
    recoveries: list[Recovery] = []
    since: float | None = None
    for t, bad in changes:
        if bad:
            since = t if since is None else since
        elif bad is not None and since is not None:
            started = [s.start for s in spans if since <= s.start <= t]
            if ws <= t <= we and (started or t - since >= debounce_s):
                recoveries.append(Recovery(clip(since), clip(min(started)) if started else None,
                                           t - ws))
            since = None

    kept = [s for s in spans if s.start <= we and (s.end is None or s.end >= ws)]
    out_spans = tuple(
        ActionSpan(s.action_id, s.action, s.args, clip(s.start),
                   None if s.end is None else clip(s.end), s.outcome, s.plan_id, s.detail)
        for s in sorted(kept, key=lambda s: (s.start, s.action_id)))
    starts = [s.start for s in out_spans]
    rows = [ComponentRow(r.name, r.group, _retracted(r.intervals, starts, debounce_s, we - ws))
            for r in rows]
    origin = entries[0].wall + ws if clock == "wall" else _wall_at(entries, ws, at)
    return Timeline(
        name=name, robot=robot, start=0.0, end=we - ws, origin_wall=origin,
        first_id=inside[0].id if inside else 0, last_id=inside[-1].id if inside else 0,
        clock=clock, rows=tuple(rows), actions=out_spans,
        plans=tuple(PlanMark(p.time - ws, p.plan_id, p.steps) for p in plans
                    if ws <= p.time <= we),
        recoveries=tuple(recoveries),
        diagnoses=sum(1 for t in diag_times if ws <= t <= we),
        window="" if start is None and end is None else f"{start or 'start'} .. {end or 'end'}",
        run=run,
        mission=clip_spans(mission_spans(entries, at, _action_time), ws, we),
        plan_diagnoses=clip_marks(diagnosis_marks(entries, at), ws, we))


def _wall_at(entries: Sequence[Entry], t: float, at: Callable[[Entry], float]) -> float:
    """The wall time at axis time ``t`` (through the first entry at or after it)."""
    for e in entries:
        if at(e) >= t:
            return e.wall - (at(e) - t)
    return entries[-1].wall + (t - at(entries[-1]))


def _intervals(comp: str, changes: Sequence[tuple[float, frozenset[str] | None]], ws: float,
               we: float) -> tuple[Interval, ...]:
    """The component's states between ``ws`` and ``we``, merged, relative to ``ws``."""
    points: list[tuple[float, HealthState]] = [(min(0.0, ws), HealthState.UNKNOWN)]
    for t, bad in changes:
        state = HealthState.UNKNOWN if bad is None else (
            HealthState.ABNORMAL if comp in bad else HealthState.NORMAL)
        points.append((t, state))
    out: list[Interval] = []
    for i, (t, state) in enumerate(points):
        nxt = points[i + 1][0] if i + 1 < len(points) else we
        a, b = max(t, ws), min(nxt, we)
        if b <= a:
            continue
        if out and out[-1].state is state and abs(out[-1].end - (a - ws)) < 1e-9:
            out[-1] = Interval(out[-1].start, b - ws, state)
        else:
            out.append(Interval(a - ws, b - ws, state))
    return tuple(out)


def _retracted(intervals: tuple[Interval, ...], action_starts: Sequence[float],
               debounce_s: float, end: float) -> tuple[Interval, ...]:
    """``intervals`` with each abnormal one shorter than ``debounce_s``, taken back before
    ``end`` and with no action started in it, marked ``RETRACTED``."""
    out = []
    for iv in intervals:
        if (iv.state is HealthState.ABNORMAL and iv.duration < debounce_s and iv.end < end - 1e-9
                and not any(iv.start <= a <= iv.end for a in action_starts)):
            iv = Interval(iv.start, iv.end, HealthState.RETRACTED)
        out.append(iv)
    return tuple(out)
