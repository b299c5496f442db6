"""Layer 3, the mission: goal reasoning, planning and dispatching until the goal holds.

``MissionRunner.run()`` is the loop of paper 001 §II-A (figure 2's Goal Reasoner, Planner and
Dispatching & Monitoring):

1. sense the world into the KB (``init``), then repeat:
2. goal reasoning — the mission's goal plus what ``goals:`` rules add for what the robot has
   learnt (a victim found must be marked: ``{when: (victim-in ?v ?r), add: (marked ?v)}``);
3. planning from the KB (``host.planning.temporal_planner``) with only the actions whose skills
   layer 0 leaves available (a quarantined lidar takes navigation away); no plan: the mission
   *stops*, and says what the planner lacked — the actions it had to leave out and the
   components behind them;
4. dispatching the plan step by step (``host.mission.dispatcher``); after a refused or failed
   action, a success the world does not show, or a goal that grew, the KB is as sensed and the
   mission replans (at most ``max_replans`` times, then it *fails*); an action that failed
   with no component to blame (the world did not let it work) is not planned again from the
   same knowledge base, so the plan goes around it or the mission stops, saying so;
5. plan-execution diagnosis (``host.plandiag.live``, when a ``diagnoser`` is given): after a
   step that did not go as planned, and when sensing takes back an effect an earlier step
   reported (a marker gone), the executed history is explained (``PlanDiagnosis`` event) and
   the KB takes what the most probable history implies (``KbChange``, source ``diagnosis``)
   before the mission replans from it.

It emits ``MissionState`` events (started, planned with its schedule, replanning, completed,
stopped, failed) and returns a ``MissionOutcome``: completed or not, why, the components blamed.
"""

from __future__ import annotations

import logging
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from typing import Protocol

from host.events import Event, MissionState, MissionStep
from host.layers import MISSION, Result
from host.mission.dispatcher import Dispatched, Dispatcher, DispatchOutcome
from host.mission.kb import KnowledgeBase
from host.planning.temporal_pddl import Atom, Literal, TemporalDomain, TemporalProblem, spell
from host.planning.temporal_planner import Ground, ground, holds, plan
from host.skills import AvailState, Layer0View

log = logging.getLogger(__name__)


@dataclass(frozen=True)
class GoalRule:
    """For every KB atom matching ``when`` (``?x`` binds), ``add`` becomes a goal."""

    when: Atom
    add: Atom

    def goals(self, atoms: set[Atom]) -> list[Literal]:
        out: list[Literal] = []
        for atom in atoms:
            if atom[0] != self.when[0] or len(atom) != len(self.when):
                continue
            binding: dict[str, str] = {}
            if all(p == a or (p.startswith("?") and binding.setdefault(p, a) == a)
                   for p, a in zip(self.when[1:], atom[1:], strict=True)):
                out.append(((self.add[0], *(binding.get(x, x) for x in self.add[1:])), True))
        return out


class Diagnoses(Protocol):
    """What the runner needs of plan-execution diagnosis (``host.plandiag.live``)."""

    def ended(self, done: Dispatched, at: float) -> None: ...

    def surprise(self) -> tuple[Literal, ...]: ...

    def explain(self, objects: Mapping[str, str], message: str,
                observed: Sequence[Literal] = ()) -> tuple[Event, tuple[Literal, ...]] | None:
        ...


@dataclass
class MissionOutcome:
    completed: bool
    detail: str = ""
    components: list[str] = field(default_factory=list)
    replans: int = 0
    actions: int = 0


class MissionRunner:
    def __init__(self, domain: TemporalDomain, problem: TemporalProblem, rules: Sequence[GoalRule],
                 kb: KnowledgeBase, dispatcher: Dispatcher,
                 needs_of: Mapping[str, Sequence[str]], layer0: Layer0View | None,
                 emit: Callable[[Event], None], mission_id: str = "m1",
                 max_replans: int = 20, diagnoser: Diagnoses | None = None) -> None:
        self.domain = domain
        self.problem = problem
        self.rules = rules
        self.kb = kb
        self.dispatcher = dispatcher
        self.needs_of = needs_of  # action -> the components and topics its skills need
        self.layer0 = layer0  # None: plan as if every skill were available (the flat system)
        self.emit = emit
        self.mission_id = mission_id
        self.max_replans = max_replans
        self.diagnoser = diagnoser
        # ground actions that failed, with nothing to blame below, from a KB state: not planned
        # again from that state (the world will not let them work there)
        self.failed: dict[tuple[str, tuple[str, ...], frozenset[Atom]], str] = {}

    def goal(self) -> tuple[Literal, ...]:
        extra = [g for rule in self.rules for g in rule.goals(self.kb.atoms)]
        return tuple(dict.fromkeys([*self.problem.goal, *extra]))

    def _state(self, state: str, detail: str = "", plan_: Sequence[MissionStep] = (),
               components: Sequence[str] = ()) -> None:
        goal = tuple(("" if pos else "not ") + spell(a) for a, pos in self.goal())
        self.emit(MissionState(self.mission_id, state, detail, goal, tuple(plan_),
                               tuple(components)))

    def _allowed(self, g: Ground) -> bool:
        if (g.name, g.args, self.kb.state()) in self.failed:
            return False
        return self.layer0 is None or self.layer0.availability(
            self.needs_of.get(g.name, ())).state is not AvailState.UNAVAILABLE

    async def run(self) -> MissionOutcome:
        self.kb.change([(a, True) for a in self.problem.init], "init", "the mission's problem")
        self._state("started")
        await self.dispatcher.sense(None, "at the start")
        replans = actions = 0
        while True:
            goal = self.goal()
            if holds(self.kb.state(), goal):
                out = MissionOutcome(True, "every goal holds", replans=replans, actions=actions)
                self._state("completed", f"{actions} actions, {replans} replans")
                return out
            grounds = ground(self.domain, self.problem, self.kb.objects, self.kb.state())
            schedule = plan(grounds, self.kb.state(), goal, self._allowed)
            if schedule is None:
                return self._stop(grounds, goal, replans, actions)
            steps = [MissionStep(s.ground.name, s.ground.args, s.start, s.ground.duration)
                     for s in schedule]
            self._state("planned", plan_=steps)
            why = ""
            for i, step in enumerate(schedule):
                before = self.kb.state()
                done = await self.dispatcher.dispatch(step, i)
                actions += 1
                if self.diagnoser is not None:
                    self.diagnoser.ended(done, self.dispatcher.clock())
                if done.outcome is not DispatchOutcome.DONE:
                    why = f"{step.ground}: {done.outcome}: {done.result.describe()}"
                    self._diagnose(why, done.dispatch_id)
                    if done.outcome is DispatchOutcome.FAILED and not done.result.components():
                        g = step.ground
                        self.failed[(g.name, g.args, before)] = done.result.describe()
                    break
                taken = () if self.diagnoser is None else self.diagnoser.surprise()
                if taken:
                    why = "the world no longer shows " + ", ".join(spell(a) for a, _ in taken) \
                        + f" (after {step.ground})"
                    self._diagnose(why, done.dispatch_id, [(a, False) for a, _ in taken])
                    break
                if self.goal() != goal:
                    why = "the goal grew: " + ", ".join(
                        spell(a) for a, _ in self.goal() if (a, True) not in goal)
                    break
            else:
                continue
            replans += 1
            if replans > self.max_replans:
                detail = f"gave up after {self.max_replans} replans; last: {why}"
                self._state("failed", detail)
                return MissionOutcome(False, detail, replans=replans, actions=actions)
            self._state("replanning", why)

    def _diagnose(self, why: str, dispatch_id: str, observed: Sequence[Literal] = ()) -> None:
        """Explain the history; the KB takes what its most probable history implies."""
        if self.diagnoser is None:
            return
        found = self.diagnoser.explain(self.kb.objects, why, observed)
        if found is None:
            return
        event, corrections = found
        self.emit(event)
        self.kb.change(corrections, "diagnosis", "plan-execution diagnosis", dispatch_id)

    def _stop(self, grounds: list[Ground], goal: tuple[Literal, ...], replans: int,
              actions: int) -> MissionOutcome:
        """No plan: say which actions the layers below took away, and why."""
        blocked: dict[str, tuple[str, tuple[str, ...]]] = {}
        if self.layer0 is not None:
            for name in sorted({g.name for g in grounds}):
                avail = self.layer0.availability(self.needs_of.get(name, ()))
                if avail.state is AvailState.UNAVAILABLE:
                    blocked[name] = (avail.why, avail.components)
        unmet = ", ".join(spell(a) for a, pos in goal if (a in self.kb.atoms) != pos)
        here = [f"{g}: {why}" for g in grounds
                if (why := self.failed.get((g.name, g.args, self.kb.state()))) is not None]
        comps: list[str] = []
        if (blocked or here) and plan(grounds, self.kb.state(), goal) is not None:
            comps = sorted({c for _, cs in blocked.values() for c in cs})
            detail = f"cannot reach {unmet}: " + "; ".join(
                [f"{a} unavailable ({why})" for a, (why, _) in blocked.items()]
                + [f"failed from here: {h}" for h in here])
        else:
            detail = f"no plan reaches {unmet} from what the robot knows"
        result = Result.fail(MISSION, detail, comps)
        self._state("stopped", result.describe(), components=comps)
        return MissionOutcome(False, detail, comps, replans, actions)
