"""Plan-execution diagnosis inside the running mission: its history recorded, explained on an
alarm, the knowledge base corrected for the replanning (paper 004 §4.3, paper 001 §III-C).

``MissionDiagnoser`` listens to the mission layer: every ``Dispatch`` event opens a step (the
ground action, the knowledge base before it, its checks), every sensing of the world
(``sensed``) adds its observations, and ``diagnose(done)`` — the runner's call after a step did
not go as planned — turns what was recorded into a ``History`` and runs the TDS pipeline
(``explain_history``) on it. The observations are placed where the diagnosis can use them: an
observation of a static atom (a victim found in a room) held all along and joins the initial
knowledge base; one made during or after a step about an atom that step's action mentions is
its expected-state check (**local**); any other is the next step's precondition check (it
says how the world was before that step ran: **propagated**), or the last step's check when
none followed. The alarm is where the dispatcher stopped: a refused dispatch at its
precondition check, a failed action during it, a halted action a critical alarm during it, a
success the world does not show at its expected-state check; and ``surprise()`` raises one
when sensing takes back an effect an earlier step established (a marker gone). The result is
a ``PlanDiagnosis`` event (classes, symptoms, region, histories, the winning path of the
context tree, the corrected knowledge base or the plan error) and the literals the mission's
knowledge base must take so that the mission replans from what the most probable history
implies.
"""

from __future__ import annotations

import logging
from collections.abc import Callable, Iterable, Mapping, Sequence
from dataclasses import dataclass, field
from enum import StrEnum
from typing import Protocol

from host.atoms import Atom
from host.events import Dispatch, Event, KbChange, PlanDiagnosis
from host.plandiag.errors import HistoryError
from host.plandiag.history import (
    Alarm,
    ComponentHealth,
    History,
    HistoryStep,
    MissionObservation,
    StepResult,
    Where,
)
from host.plandiag.model import PlanModel
from host.plandiag.pipeline import Explanation, explain_history
from host.plandiag.text import listing, winning_path
from host.planning.temporal_pddl import Literal, TemporalDomain, parse_atom

log = logging.getLogger(__name__)


class EndedStep(Protocol):
    """What ``MissionDiagnoser.ended`` reads of a dispatcher's end of a step (the mission
    layer's ``host.mission.dispatcher.Dispatched`` is one), so that plan-execution diagnosis
    does not import the layer it diagnoses."""

    @property
    def dispatch_id(self) -> str: ...

    @property
    def outcome(self) -> str: ...  # one of ``Ending``'s values but HALTED

    @property
    def halted(self) -> bool: ...

    @property
    def alarm(self) -> tuple[Literal, ...]: ...


class Ending(StrEnum):
    """How the dispatcher ended a step (``host.mission.dispatcher.Outcome``'s values)."""

    DONE = "done"
    REFUSED = "refused"
    FAILED = "failed"
    HALTED = "halted"
    SURPRISE = "surprise"


def to_atom(a: tuple[str, ...]) -> Atom:
    return Atom(a[0], tuple(a[1:]))


def to_literal(text: str) -> Literal:
    """``~open(door_office)`` -> ``(("open", "door_office"), False)``."""
    a = Atom.parse(text.lstrip("~"))
    return (a.predicate, *a.args), not text.startswith("~")


@dataclass
class _Record:
    dispatch_id: str
    action: str
    args: tuple[str, ...]
    kb: tuple[str, ...]
    failed: tuple[Literal, ...]  # what a refusing check found: the conditions' opposites
    ok: bool
    start: float
    end: float | None = None
    ending: Ending | None = None
    seen: dict[tuple[str, ...], bool] = field(default_factory=dict)  # last value per atom
    alarm_atoms: tuple[Literal, ...] = ()


@dataclass(frozen=True)
class Diagnosed:
    explanation: Explanation
    event: PlanDiagnosis
    corrections: tuple[Literal, ...]  # what the KB must take beyond what was observed


class MissionDiagnoser:
    """The mission layer's plan-execution diagnosis: record, explain on an alarm, correct."""

    def __init__(self, model: PlanModel, domain: TemporalDomain, mission_id: str,
                 health: Callable[[], ComponentHealth] = ComponentHealth,
                 engine: str = "sat") -> None:
        self.model = model
        self.domain = domain
        self.mission_id = mission_id
        self.health = health
        self.engine = engine
        self.records: list[_Record] = []
        self.at_start: dict[tuple[str, ...], bool] = {}
        self.established: set[str] = set()  # atoms an effect made true, still believed
        self.taken_back: list[Literal] = []  # established effects sensing took back
        self.static = set(model.domain.statics)
        self.last: Diagnosed | None = None  # the latest diagnosis

    # -- recording ---------------------------------------------------------------------------
    def on_event(self, e: Event) -> None:
        match e:
            case Dispatch():
                failed = tuple((parse_atom(c.atom), not c.expected) for c in e.failed_checks)
                self.records.append(_Record(e.dispatch_id, e.action, e.args, e.kb, failed,
                                            e.ok, e.at))
            case KbChange(source="effect"):
                self.established |= set(e.added)
                self.established -= set(e.removed)
            case KbChange(source="sensing"):
                gone = [a for a in e.removed if a in self.established]
                self.established -= set(e.removed)
                self.taken_back += [(parse_atom(a), True) for a in gone]

    def sensed(self, lits: Iterable[Literal], dispatch_id: str = "") -> None:
        """Observations of the world, made during or after ``dispatch_id`` (none: the start)."""
        rec = self._record(dispatch_id)
        seen = self.at_start if rec is None else rec.seen
        for atom, value in lits:
            seen[atom] = value

    def ended(self, done: EndedStep, at: float) -> None:
        """The dispatcher's end of a step: how, when, what it observed that raised an alarm."""
        rec = self._record(done.dispatch_id)
        if rec is not None:
            ending = Ending.HALTED if done.halted else Ending(done.outcome)
            rec.ending, rec.end, rec.alarm_atoms = ending, at, done.alarm

    def surprise(self) -> tuple[Literal, ...]:
        """Effects reported achieved that sensing has since taken back (cleared on reading)."""
        out, self.taken_back = tuple(self.taken_back), []
        return out

    def _record(self, dispatch_id: str) -> _Record | None:
        for rec in reversed(self.records):
            if rec.dispatch_id == dispatch_id:
                return rec
        return None

    # -- the history -----------------------------------------------------------------------
    def history(self, objects: Mapping[str, str], message: str = "",
                observed: Sequence[Literal] = ()) -> History:
        """The executed history up to the last step, its alarm where that step ended (or at
        its expected-state check with ``observed`` as the alarm's atoms: a surprise)."""
        last = self.records[-1] if self.records else None
        recs = [r for r in self.records if r.ok or r is last]
        if last is None or not recs:
            raise HistoryError("nothing was dispatched yet", "diagnose after a step")
        init = {to_atom(parse_atom(a)) for a in recs[0].kb}
        pre: list[list[MissionObservation]] = [[] for _ in recs]
        post: list[list[MissionObservation]] = [[] for _ in recs]
        for atom, value in self.at_start.items():
            self._place(atom, value, init, pre[0], Where.PRE, None)
        for i, rec in enumerate(recs):
            mentioned = self._mentioned(rec)
            for atom, value in rec.seen.items():
                if atom in mentioned or i + 1 == len(recs):
                    self._place(atom, value, init, post[i], Where.POST, rec.end)
                else:
                    self._place(atom, value, init, pre[i + 1], Where.PRE, rec.end)
        steps = []
        for i, rec in enumerate(recs):
            result = _RESULT[rec.ending or Ending.DONE] if rec.ok else StepResult.NOT_RUN
            obs = pre[i] + (post[i] if rec.ok else [])
            if not rec.ok:  # what the check found: the KB the dispatcher held
                have = {o.atom for o in obs}
                obs += [MissionObservation(to_atom(a), v, Where.PRE, rec.start, "check")
                        for a, v in rec.failed if to_atom(a) not in have]
            steps.append(HistoryStep(rec.action, rec.args, result, tuple(obs), rec.start, rec.end))
        alarm = self._alarm(len(steps), last, message, observed)
        return History(dict(objects), frozenset(init), tuple(steps), alarm, self.health())

    def _place(self, atom: tuple[str, ...], value: bool, init: set[Atom],
               into: list[MissionObservation], where: Where, t: float | None) -> None:
        a = to_atom(atom)
        if atom[0] in self.static:
            if value:
                init.add(a)  # it held all along (a victim found where it lies)
            return
        into.append(MissionObservation(a, value, where, t, "sensing"))

    def _mentioned(self, rec: _Record) -> set[tuple[str, ...]]:
        """The ground atoms the step's action names in its conditions and effects."""
        act = self.domain.actions.get(rec.action)
        if act is None:
            return set()
        binding = dict(zip(act.param_names, rec.args, strict=False))
        return {(a[0], *(binding.get(x, x) for x in a[1:]))
                for lits in [*act.cond.values(), *act.eff.values()] for a, _ in lits}

    def _alarm(self, n: int, last: _Record, message: str, observed: Sequence[Literal]
               ) -> Alarm:
        atoms = tuple((to_atom(a), v) for a, v in (observed or last.alarm_atoms))
        if not last.ok:
            atoms = tuple((to_atom(a), v) for a, v in last.failed)
            return Alarm(n, Where.PRE, False, atoms, message, last.start)
        if observed or last.ending in (Ending.SURPRISE, Ending.DONE, None):
            return Alarm(n, Where.POST, False, atoms, message, last.end)
        return Alarm(n, Where.DURING, last.ending is Ending.HALTED, atoms, message, last.end)

    # -- diagnosis ---------------------------------------------------------------------------
    def explain(self, objects: Mapping[str, str], message: str,
                observed: Sequence[Literal] = ()) -> tuple[Event, tuple[Literal, ...]] | None:
        """The runner's call: the diagnosis as an event and the KB's corrections."""
        d = self.diagnose(objects, message, observed)
        self.taken_back = []  # explained now, with everything sensed so far
        if d is not None:
            self.last = d
        return None if d is None else (d.event, d.corrections)

    def diagnose(self, objects: Mapping[str, str], message: str = "",
                 observed: Sequence[Literal] = ()) -> Diagnosed | None:
        """Explain the history up to now; None when it cannot be (logged)."""
        try:
            history = self.history(objects, message, observed)
            e = explain_history(self.model, history, self.engine)
        except HistoryError as exc:
            log.warning("plan-execution diagnosis impossible: %s", exc)
            return None
        return Diagnosed(e, self._event(e, message), corrections(e))

    def _event(self, e: Explanation, message: str) -> PlanDiagnosis:
        p = e.context.problem
        last = self.records[-1]
        kb: list[str] = []
        if e.kb is not None:
            certain = set(e.kb.certain)
            kb = [f"{x} (observed)" for x in e.kb.observed] + [
                x + ("" if x in certain else " (probable)") for x in e.kb.changes()]
        pe = e.plan_error
        pe_text = "" if pe is None else f"plan error at step {pe.step} {pe.label}: {pe.reason}" \
            + "".join(f"; the domain may lack {c.literal} ({c.ground})" for c in pe.conditions)
        return PlanDiagnosis(
            self.mission_id, last.dispatch_id, e.alarm.alarm.step, message,
            [c.value for c in e.classes()], [f"{s.kind.value}: {s.text}" for s in e.symptoms],
            "" if e.region is None else e.region.describe(p)
            + (" (nothing in it explains the alarm: searched the whole history)"
               if e.widened else ""),
            listing(e.histories), winning_path(e, e.histories[0]) if e.histories else [],
            kb, pe_text, round(e.elapsed_s, 4))


_RESULT = {Ending.DONE: StepResult.SUCCESS, Ending.SURPRISE: StepResult.SUCCESS,
           Ending.FAILED: StepResult.FAIL, Ending.HALTED: StepResult.HALTED,
           Ending.REFUSED: StepResult.NOT_RUN}


def corrections(e: Explanation) -> tuple[Literal, ...]:
    """The literals the most probable history implies beyond what was observed."""
    if e.kb is None:
        return ()
    return tuple(to_literal(x) for x in e.kb.changes())


