"""The mission's temporal planner: grounding and an optimal search, a schedule of ⟨a, t_a, d_a⟩.

One robot does one action at a time, so a plan is a sequence and its schedule starts each
action when the one before ends (action, start, duration — paper 001 §II-A). An action is
applicable in a state S when its start and over-all conditions hold in S, and its end and
over-all conditions hold once its start effects are applied; its end effects then give the next
state (the "temporally simple" reading of PDDL 2.1: no plan here needs two actions at once).

``ground(domain, problem)`` instantiates every action over the typed objects, pruning with the
static atoms (predicates no action changes, e.g. which door connects which rooms); the static
conditions stay in the ground action, so that a dispatch checks and records them too. ``plan``
is A* on states (frozen sets of true atoms; closed world), the cost of an action its duration,
with an admissible heuristic (goal literals unmet, divided by the most any one action achieves,
times the shortest duration). ``allowed`` drops ground actions a layer below cannot carry out
now (a skill unavailable: its lidar quarantined), so the plan goes around them or there is
none. It returns ``None`` when no plan exists within ``max_nodes`` states.
"""

from __future__ import annotations

import heapq
import itertools
import logging
import math
from collections.abc import Callable, Iterable
from dataclasses import dataclass

from host.planning.temporal_pddl import Action, Atom, Literal, TemporalDomain, TemporalProblem

log = logging.getLogger(__name__)

State = frozenset[Atom]


@dataclass(frozen=True)
class Ground:
    """One ground action: its conditions and effects on atoms."""

    action: Action
    args: tuple[str, ...]
    cond: dict[str, tuple[Literal, ...]]
    eff: dict[str, tuple[Literal, ...]]

    @property
    def name(self) -> str:
        return self.action.name

    @property
    def duration(self) -> float:
        return self.action.duration

    def __str__(self) -> str:
        return f"{self.name}({', '.join(self.args)})"

    def __hash__(self) -> int:
        return hash((self.name, self.args))

    def __eq__(self, other: object) -> bool:
        return isinstance(other, Ground) and (self.name, self.args) == (other.name, other.args)


@dataclass(frozen=True)
class Scheduled:
    ground: Ground
    start: float

    @property
    def end(self) -> float:
        return self.start + self.ground.duration


def holds(state: State, lits: Iterable[Literal]) -> bool:
    return all((atom in state) == pos for atom, pos in lits)


def apply(state: State, lits: Iterable[Literal]) -> State:
    lits = list(lits)
    removed = {a for a, pos in lits if not pos}
    added = {a for a, pos in lits if pos}
    return frozenset((state - removed) | added)


def applicable(state: State, g: Ground) -> State | None:
    """The state after ``g`` if it can run from ``state``, else None."""
    if not holds(state, g.cond["start"]) or not holds(state, g.cond["over all"]):
        return None
    mid = apply(state, g.eff["start"])
    if not holds(mid, g.cond["over all"]) or not holds(mid, g.cond["end"]):
        return None
    return apply(mid, g.eff["end"])


def _static(domain: TemporalDomain) -> set[str]:
    changed = {a[0] for act in domain.actions.values() for lits in act.eff.values()
               for a, _ in lits}
    return set(domain.predicates) - changed


def ground(domain: TemporalDomain, problem: TemporalProblem, objects: dict[str, str] | None = None,
           init: frozenset[Atom] | None = None) -> list[Ground]:
    """Every ground action whose static conditions hold in ``init``."""
    objects = problem.objects if objects is None else objects
    init = problem.init if init is None else init
    static = _static(domain)
    out: list[Ground] = []
    for act in domain.actions.values():
        choices = [[o for o, t in objects.items() if domain.is_a(t, typ)]
                   for _, typ in act.params]
        names = act.param_names
        for values in itertools.product(*choices):
            binding = dict(zip(names, values, strict=True))

            def sub(lits: tuple[Literal, ...], b: dict[str, str] = binding
                    ) -> tuple[Literal, ...]:
                return tuple(((a[0], *(b.get(x, x) for x in a[1:])), pos) for a, pos in lits)

            cond = {k: sub(v) for k, v in act.cond.items()}
            fixed = [lit for lits in cond.values() for lit in lits if lit[0][0] in static]
            if not holds(init, fixed):
                continue
            out.append(Ground(act, tuple(values), cond, {k: sub(v) for k, v in act.eff.items()}))
    return out


def plan(actions: list[Ground], init: State, goal: tuple[Literal, ...],
         allowed: Callable[[Ground], bool] | None = None,
         max_nodes: int = 200_000) -> list[Scheduled] | None:
    """An optimal schedule from ``init`` to ``goal`` (total duration), or None."""
    acts = [g for g in actions if allowed is None or allowed(g)]
    if holds(init, goal):
        return []
    gains = [sum(1 for lit in goal if lit in g.eff["end"] or lit in g.eff["start"])
             for g in acts]
    best_gain = max([1, *gains])
    shortest = min([g.duration for g in acts if g.duration > 0] or [0.0])

    def h(state: State) -> float:
        unmet = sum(1 for atom, pos in goal if (atom in state) != pos)
        return math.ceil(unmet / best_gain) * shortest

    counter = itertools.count()
    frontier: list[tuple[float, int, float, State]] = [(h(init), next(counter), 0.0, init)]
    parent: dict[State, tuple[State, Ground] | None] = {init: None}
    cost: dict[State, float] = {init: 0.0}
    expanded = 0
    while frontier:
        _, _, g_cost, state = heapq.heappop(frontier)
        if g_cost > cost.get(state, math.inf):
            continue
        if holds(state, goal):
            return _schedule(parent, state)
        expanded += 1
        if expanded > max_nodes:
            log.warning("planning gave up after %d states", max_nodes)
            return None
        for act in acts:
            nxt = applicable(state, act)
            if nxt is None:
                continue
            c = g_cost + act.duration
            if c < cost.get(nxt, math.inf):
                cost[nxt] = c
                parent[nxt] = (state, act)
                heapq.heappush(frontier, (c + h(nxt), next(counter), c, nxt))
    return None


def _schedule(parent: dict[State, tuple[State, Ground] | None], state: State
              ) -> list[Scheduled]:
    steps: list[Ground] = []
    link = parent[state]
    while link is not None:
        prev, act = link
        steps.append(act)
        link = parent[prev]
    out: list[Scheduled] = []
    t = 0.0
    for act in reversed(steps):
        out.append(Scheduled(act, t))
        t += act.duration
    return out
