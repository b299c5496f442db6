"""The context tree (paper 004 §4.3.1.6): plan-execution inference by simulating alternatives.

Nodes are states, arcs are what happened between two points: a set of exogenous events in a
gap, then the step's nominal action or one of its fault modes. The root is the initial
knowledge base; a path from the root to the last point is an alternative history. Each node's
children are generated together and those that contradict the observations at their point are
dropped at once (breadth-first per step); the search then goes depth-first along a child that
matches what was observed, the nominal one first and then by prior, and backtracks when a path
runs into a contradiction with the alarm environment.

The minimal diagnoses come level by level: level ``k`` lists the histories with at most ``k``
faults that are no superset of one found before (so each is subset-minimal, as in layer 0's
``cardinality`` search). A node ``(point, state)`` from which no consistent completion with
``b`` more faults exists is remembered and never expanded again with budget ``b`` or less; a
node with no budget left is followed along its one nominal completion without branching. Only
the faults in ``universe`` (the fault region's suspects, or all) are tried; the other steps are
simulated as intended, as the paper keeps irrelevant actions in the tree for coherence.
``nodes`` counts the expanded nodes (the benchmark's measure of the region's pruning).
"""

from __future__ import annotations

import itertools
import sys
from collections.abc import Iterator
from contextlib import contextmanager
from enum import Enum

from host.diagnosis.result import Bound
from host.plandiag.limits import Deadline, ExplainOutcome, Limits
from host.plandiag.problem import HistoryProblem, apply_events
from host.plandiag.sat import any_beyond
from host.planning.task import GroundOp


class _Stop(Exception):
    """A bound (count or time) ended the search."""


class _Hit(Exception):
    """The probe found what it looked for."""


class _Mode(Enum):
    RECORD = 1  # list every leaf as a diagnosis
    PROBE = 2  # stop at the first leaf


class ContextTree:
    def __init__(self, problem: HistoryProblem, universe: frozenset[int] | None, limits: Limits):
        self.p = problem
        self.limits = limits
        self.universe = universe
        allowed = (lambda f: True) if universe is None else universe.__contains__
        by_prior = sorted(range(len(problem.faults)), key=lambda f: -problem.faults[f].prior)
        rank = {f: r for r, f in enumerate(by_prior)}
        self.modes = {s.index: sorted((f for f in s.modes if allowed(f)), key=rank.__getitem__)
                      for s in problem.steps}
        self.events = [sorted((f for f in g if allowed(f)), key=rank.__getitem__)
                       for g in problem.gaps]
        self.dead: dict[tuple[int, int], int] = {}  # (point, state) -> largest dead budget
        self.tail: dict[tuple[int, int], bool] = {}  # nominal completion consistent?
        self.found: list[frozenset[int]] = []
        self.nodes = 0
        self.deadline = Deadline(limits.time_budget_s)
        self.out = ExplainOutcome()

    # -- the search -----------------------------------------------------------------------
    def run(self) -> ExplainOutcome:
        out = self.out
        p = self.p
        total = sum(len(m) > 0 for m in self.modes.values()) + sum(map(len, self.events))
        limit = total if self.limits.max_card is None else min(self.limits.max_card, total)
        with _deep_recursion(4 * len(p.steps) + 200):
            try:
                if not p.obs_ok(0, p.init) or p.impossible_step(self.universe) is not None:
                    return self._done()  # complete and empty: proven unexplainable
                for k in range(limit + 1):
                    self._dfs(0, p.init, (), k, _Mode.RECORD)
                    if frozenset() in self.found:  # nothing went wrong: the only diagnosis
                        return self._done()
                if limit < total:
                    more = self.beyond(limit + 1) or any_beyond(
                        p, self.universe, self.found, self.deadline.left())
                    if more is None or more:
                        out.cut_by = Bound.TIME_BUDGET if more is None else Bound.MAX_CARD
            except _Stop:
                pass
        return self._done()

    def _done(self) -> ExplainOutcome:
        self.out.diagnoses = list(self.found)
        self.out.nodes = self.nodes
        return self.out

    def beyond(self, budget: int) -> bool:
        """Is there a consistent history with at most ``budget`` faults that is no superset
        of a diagnosis found? (Asked one level beyond ``max_card``: such a history is a
        minimal diagnosis the bound left out. Consistency is not monotone, so none there
        does not prove none beyond: ``sat.any_beyond`` settles that in one solver call.)"""
        try:
            self._dfs(0, self.p.init, (), budget, _Mode.PROBE)
        except _Hit:
            return True
        return False

    def _blocked(self, chosen: tuple[int, ...]) -> bool:
        s = set(chosen)
        return any(d <= s for d in self.found)

    def _leaf(self, chosen: tuple[int, ...], mode: _Mode) -> None:
        if self._blocked(chosen):  # found before (the fault-free path at every level)
            return
        if mode is _Mode.PROBE:
            raise _Hit
        limits = self.limits
        if limits.max_count is not None and len(self.found) >= limits.max_count:
            self.out.cut_by = Bound.MAX_COUNT
            raise _Stop
        self.found.append(frozenset(chosen))

    def _dfs(self, point: int, state: int, chosen: tuple[int, ...], budget: int,
             mode: _Mode) -> bool:
        """Explore below ``(point, state)`` (an even point: before a gap) with ``budget`` more
        faults, calling ``_leaf`` for every consistent history that is no superset of a
        diagnosis found. True when some consistent completion exists or may exist (a path
        into a superset of a diagnosis is not followed), False when none does."""
        p = self.p
        if point >= p.last_point:
            self._leaf(chosen, mode)
            return True
        key = (point, state)
        if self.dead.get(key, -1) >= budget:
            return False
        if budget == 0:
            ok = self._nominal_tail(point, state)
            if ok:
                self._leaf(chosen, mode)
            return ok
        self.nodes += 1
        if self.deadline.passed():
            self.out.cut_by = Bound.TIME_BUDGET
            raise _Stop
        alive = False
        for kids, leaf in self._children(point, state, budget):
            for nxt_point, nxt_state, faults in kids:
                now = chosen + faults
                if faults and self._blocked(now):
                    alive = True  # not followed: it may well go on consistently
                elif leaf:
                    self._leaf(now, mode)
                    alive = True
                elif self._dfs(nxt_point, nxt_state, now, budget - len(faults), mode):
                    alive = True
        if not alive:
            self.dead[key] = max(self.dead.get(key, -1), budget)
        return alive

    def _children(self, point: int, state: int,
                  budget: int) -> Iterator[tuple[list[tuple[int, int, tuple[int, ...]]], bool]]:
        """Per event set of the coming gap (breadth-first: all generated and checked against
        the observations before any is followed): the consistent children after the step,
        and whether they are leaves (the step did not run: its precondition check ends it)."""
        p = self.p
        i = point // 2 + 1
        spec = p.steps[i - 1]
        pre_point, post_point = 2 * i - 1, 2 * i
        after_gap: list[tuple[int, tuple[int, ...]]] = []
        for events in self._event_sets(i, state, budget):
            s1 = apply_events(state, [p.faults[f].op for f in events])
            if s1 is not None and p.obs_ok(pre_point, s1):
                after_gap.append((s1, events))
        for s1, events in after_gap:
            if not spec.executed or pre_point >= p.last_point:
                yield [(pre_point, s1, events)], True
                continue
            kids: list[tuple[int, int, tuple[int, ...]]] = []
            left = budget - len(events)
            variants: list[tuple[GroundOp, tuple[int, ...]]] = []
            if spec.nominal is not None:
                variants.append((spec.nominal, ()))
            if left > 0:
                variants += [(p.faults[f].op, (f,)) for f in self.modes[i]]
            for op, mode in variants:
                if op.applicable(s1):
                    s2 = op.apply(s1)
                    if p.obs_ok(post_point, s2):
                        kids.append((post_point, s2, events + mode))
            yield kids, False

    def _event_sets(self, gap: int, state: int, budget: int) -> Iterator[tuple[int, ...]]:
        yield ()
        live = [f for f in self.events[gap - 1] if self.p.faults[f].op.applicable(state)]
        for size in range(1, min(budget, len(live)) + 1):
            yield from itertools.combinations(live, size)

    def _nominal_tail(self, point: int, state: int) -> bool:
        """Is the completion without any further fault consistent? (memoised)"""
        p = self.p
        key = (point, state)
        known = self.tail.get(key)
        if known is not None:
            return known
        seen = [key]
        ok = True
        while point < p.last_point:
            i = point // 2 + 1
            spec = p.steps[i - 1]
            if not p.obs_ok(2 * i - 1, state):
                ok = False
                break
            if not spec.executed or 2 * i - 1 >= p.last_point:
                break
            op = spec.nominal
            if op is None or not op.applicable(state):
                ok = False
                break
            state = op.apply(state)
            point = 2 * i
            if not p.obs_ok(point, state):
                ok = False
                break
            known = self.tail.get((point, state))
            if known is not None:
                ok = known
                break
            seen.append((point, state))
        for k in seen:
            self.tail[k] = ok
        return ok


def context_tree(problem: HistoryProblem, universe: frozenset[int] | None,
                 limits: Limits) -> ExplainOutcome:
    return ContextTree(problem, universe, limits).run()


@contextmanager
def _deep_recursion(depth: int) -> Iterator[None]:
    """One frame per step: long histories need more than Python's default 1000."""
    old = sys.getrecursionlimit()
    sys.setrecursionlimit(max(old, depth))
    try:
        yield
    finally:
        sys.setrecursionlimit(old)
