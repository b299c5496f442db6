"""Our planners: optimal A* over a pruned task, behind a name -> callable registry.

Stage four of the pipeline (pyperplan's ``search`` step). ``astar`` is cost-optimal and fast
on repair tasks because of two pruning methods that both keep an optimal plan:

* *backward relevance* (``relevant_ops``): only operators that can make a literal true that
  the goal or a relevant operator needs are kept; literals true in I are followed only once a
  kept operator can falsify them, and both values of every condition of a kept conditional
  effect are relevant (a plan may need to prevent a side effect, e.g. stop a driver before
  its device is switched). A single fault among 2,000 components leaves a handful.
* *strong stubborn sets* (Alkhazraji et al. 2012, ``_stubborn``): in each state only the
  applicable operators of a stubborn set are expanded, so independent repairs (power up ten
  devices) are not tried in every order. Interference is over-approximated (two operators
  interfere when one writes an atom the other reads or writes, conditions included), which
  keeps it sound with conditional effects.

The heuristic is the number of unsatisfied goal literals divided by the most any one operator
achieves, times the cheapest operator cost: admissible for any task. ``bfs`` is breadth-first
search without pruning, the reference the tests compare against. A planner takes a
``SearchInput`` and returns operator indices into the task, or ``None`` when no plan exists.
"""

from __future__ import annotations

import heapq
import itertools
import logging
import math
from collections import deque
from collections.abc import Callable, Collection, Iterable, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path

from host.planning.errors import PlanningLimitError
from host.planning.task import GroundOp, Task, holds, masks

log = logging.getLogger(__name__)

DEFAULT_MAX_EXPANSIONS = 200_000
REPRUNE_BRANCHING = 16  # recompute relevance when a stubborn set keeps more applicable ops
REPRUNE_DEPTH = 8  # ... and the operator set was computed at least this many steps ago


@dataclass(frozen=True)
class SearchInput:
    """What a planner gets: the task, the initial state, the goal literals, and for planners
    that read files (Fast Downward) the domain file and the problem's PDDL text."""

    task: Task
    init: int
    goal: tuple[int, ...]
    domain_path: Path | None = None
    problem_pddl: str | None = None
    max_expansions: int = DEFAULT_MAX_EXPANSIONS
    relevant: list[int] | None = None  # relevant_ops(), when the caller computed it already


@dataclass
class SearchResult:
    ops: list[int] | None
    stats: dict[str, float] = field(default_factory=dict)


Planner = Callable[[SearchInput], SearchResult]


def relevant_ops(task: Task, init: int, goal: Sequence[int]) -> list[int]:
    """The operators a plan may need (see the module docstring); sorted indices."""
    return _relevant(task.ops, task.achievers(), init, goal)


def relevant_ops_within(task: Task, state: int, goal: Sequence[int], ix: _Index) -> list[int]:
    """``relevant_ops`` from ``state`` among the operators of ``ix`` (a relevant set of an
    ancestor state, which is closed under the same rules, so nothing is lost)."""
    return _relevant(task.ops, ix.ach, state, goal)


def _relevant(
    ops: Sequence[GroundOp], ach: Mapping[int, list[int]], init: int, goal: Sequence[int]
) -> list[int]:
    relevant: set[int] = set()
    active: set[int] = set()  # literals whose achievers are followed
    deferred: set[int] = set()  # relevant literals true in I that nothing kept falsifies yet
    threatened: set[int] = set()  # literals some kept operator can falsify
    work: list[int] = []

    def need(x: int) -> None:
        if x in active:
            return
        if (init >> (x >> 1) & 1) == (x & 1) and x not in threatened:
            deferred.add(x)
        else:
            deferred.discard(x)
            active.add(x)
            work.append(x)

    for g in goal:
        need(g)
    while work:
        x = work.pop()
        for i in ach.get(x, ()):
            if i in relevant:
                continue
            relevant.add(i)
            op = ops[i]
            for e in op.effect_literals():
                threatened.add(e ^ 1)
                if e ^ 1 in deferred:
                    need(e ^ 1)
            for p in op.pre:
                need(p)
            for c in op.cond:
                for p in c.cond:
                    need(p)
                    need(p ^ 1)
    return sorted(relevant)


class _Index:
    """Achievers, readers and writers restricted to a set of operators."""

    def __init__(self, task: Task, subset: Iterable[int]):
        self.ops = task.ops
        self.subset = list(subset)
        self.ach: dict[int, list[int]] = {}
        self.readers: dict[int, list[int]] = {}
        self.writers: dict[int, list[int]] = {}
        for i in self.subset:
            op = self.ops[i]
            for x in op.effect_literals():
                self.ach.setdefault(x, []).append(i)
            for a in op.read_atoms():
                self.readers.setdefault(a, []).append(i)
            for a in op.write_atoms():
                self.writers.setdefault(a, []).append(i)
        self._interferers: dict[int, set[int]] = {}

    def interferers(self, i: int) -> set[int]:
        got = self._interferers.get(i)
        if got is None:
            op = self.ops[i]
            got = set()
            for a in op.read_atoms():
                got.update(self.writers.get(a, ()))
            for a in op.write_atoms():
                got.update(self.writers.get(a, ()))
                got.update(self.readers.get(a, ()))
            got.discard(i)
            self._interferers[i] = got
        return got


def _stubborn(ix: _Index, state: int, goal_t: int, goal_f: int) -> list[int]:
    """The applicable operators of a strong stubborn set for ``state`` (goal not reached)."""
    unsat = (goal_t & ~state) | (goal_f & state)
    atom = (unsat & -unsat).bit_length() - 1
    g = 2 * atom + (1 if goal_t >> atom & 1 else 0)
    todo = list(ix.ach.get(g, ()))
    stubborn = set(todo)
    applicable: list[int] = []
    ops, ach = ix.ops, ix.ach
    while todo:
        i = todo.pop()
        op = ops[i]
        if op.applicable(state):
            applicable.append(i)
            new: Collection[int] = ix.interferers(i)
        else:
            # an unmet precondition whose achievers are in the set already keeps it small
            options = [ach.get(x, []) for x in op.pre if not holds(x, state)]
            new = min(options, key=len)
            for o in options:
                if all(j in stubborn for j in o):
                    new = o
                    break
        for j in new:
            if j not in stubborn:
                stubborn.add(j)
                todo.append(j)
    return applicable


def astar(inp: SearchInput, prune: bool = True) -> SearchResult:
    """Cost-optimal A* (relevance pruning and strong stubborn sets when ``prune``)."""
    task, init = inp.task, inp.init
    if not prune:
        subset: Iterable[int] = range(len(task.ops))
    elif inp.relevant is not None:
        subset = inp.relevant
    else:
        subset = relevant_ops(task, init, inp.goal)
    ix = _Index(task, subset)
    goal_t, goal_f = masks(inp.goal)
    goal_set = set(inp.goal)
    per_op = max(
        (sum(1 for x in task.ops[i].effect_literals() if x in goal_set) for i in ix.subset),
        default=1,
    )
    min_cost = min((task.ops[i].cost for i in ix.subset), default=1.0)

    def h(s: int) -> float:
        unsat = ((goal_t & ~s) | (goal_f & s)).bit_count()
        return math.ceil(unsat / max(per_op, 1)) * min_cost

    stats: dict[str, float] = {
        "relevant_ops": len(ix.subset), "expanded": 0, "generated": 0, "repruned": 0}
    best_g: dict[int, float] = {init: 0.0}
    parent: dict[int, tuple[int, int]] = {}
    # the operator set a state's successors are drawn from, and the depth it was computed at
    index_of: dict[int, tuple[_Index, int]] = {init: (ix, 0)}
    tie = itertools.count()
    h0 = h(init)
    heap: list[tuple[float, float, int, int, float, int]] = [(h0, h0, next(tie), init, 0.0, 0)]
    while heap:
        _f, _h, _t, s, g, depth = heapq.heappop(heap)
        if g > best_g.get(s, math.inf):
            continue
        if (s & goal_t) == goal_t and not (s & goal_f):
            stats["cost"] = g
            return SearchResult(_path(parent, s, init), stats)
        stats["expanded"] += 1
        if stats["expanded"] > inp.max_expansions:
            raise PlanningLimitError(
                f"A* expanded {inp.max_expansions} states without a plan; "
                "raise max_expansions or try another planner"
            )
        sx, since = index_of.get(s, (ix, 0))
        if not prune:
            succ = [i for i in sx.subset if task.ops[i].applicable(s)]
        else:
            succ = _stubborn(sx, s, goal_t, goal_f)
            if len(succ) > REPRUNE_BRANCHING and depth - since >= REPRUNE_DEPTH:
                # relevance from this state is a valid operator set for its whole subtree
                # (see relevant_ops): recompute it when stubborn sets stop being small
                smaller = relevant_ops_within(task, s, inp.goal, sx)
                if len(smaller) < len(sx.subset):
                    sx, since = _Index(task, smaller), depth
                    stats["repruned"] += 1
                    succ = _stubborn(sx, s, goal_t, goal_f)
        for i in succ:
            op = task.ops[i]
            t = op.apply(s)
            gt = g + op.cost
            if gt < best_g.get(t, math.inf):
                best_g[t] = gt
                parent[t] = (s, i)
                index_of[t] = (sx, since)
                ht = h(t)
                stats["generated"] += 1
                heapq.heappush(heap, (gt + ht, ht, next(tie), t, gt, depth + 1))
    return SearchResult(None, stats)


def bfs(inp: SearchInput) -> SearchResult:
    """Breadth-first search over every operator: shortest plans, no pruning (a reference)."""
    task, init = inp.task, inp.init
    goal_t, goal_f = masks(inp.goal)
    parent: dict[int, tuple[int, int]] = {}
    seen = {init}
    queue = deque([init])
    expanded = 0
    while queue:
        s = queue.popleft()
        if (s & goal_t) == goal_t and not (s & goal_f):
            return SearchResult(_path(parent, s, init), {"expanded": expanded})
        expanded += 1
        if expanded > inp.max_expansions:
            raise PlanningLimitError(f"BFS expanded {inp.max_expansions} states without a plan")
        for i, op in enumerate(task.ops):
            if op.applicable(s):
                t = op.apply(s)
                if t not in seen:
                    seen.add(t)
                    parent[t] = (s, i)
                    queue.append(t)
    return SearchResult(None, {"expanded": expanded})


def _path(parent: dict[int, tuple[int, int]], s: int, init: int) -> list[int]:
    out: list[int] = []
    while s != init:
        s, i = parent[s]
        out.append(i)
    out.reverse()
    return out
