"""The search engines by name, and the checks every engine's plan passes before anyone runs it.

``PLANNERS`` is the registry (pyperplan's name -> callable, house style 15): our optimal A* and
its BFS baseline (``search``) and Fast Downward (``downward``, when installed); each takes a
``SearchInput`` and returns a ``SearchResult``. ``unreachable`` is the relaxed reachability test
that names the goal literals no sequence of operators can make true, even ignoring their
harmful effects (so a planner is not asked to prove the impossible by exhausting its budget),
and ``validate`` replays a returned sequence on the task step by step, whichever engine found
it. The repair planner (``host.repair.planner``) and the problem-file planner
(``problem_file``) both plan through here.
"""

from __future__ import annotations

from collections.abc import Iterable

from host.errors import DxboardError
from host.planning.downward import fast_downward
from host.planning.search import Planner, astar, bfs
from host.planning.task import GroundOp, Task, holds

# the search engines a plan can be found with: ours (optimal A*, a BFS baseline) and Fast
# Downward (the benchmark baseline, when installed)
PLANNERS: dict[str, Planner] = {
    "astar": astar,
    "bfs": bfs,
    "fast-downward": fast_downward,
}


def unreachable(
    task: Task, init: int, goal: Iterable[int], subset: Iterable[int]
) -> list[int]:
    """Goal literals not reachable even ignoring the operators' harmful effects."""
    goal = list(goal)
    ops = task.ops
    reached: set[int] = set()
    for x in goal:
        if holds(x, init):
            reached.add(x)
    waiting: dict[int, list[int]] = {}
    missing_count: dict[int, int] = {}
    queue: list[int] = []
    for i in subset:
        pre = [x for x in ops[i].pre if not holds(x, init)]
        missing_count[i] = len(pre)
        for x in pre:
            waiting.setdefault(x, []).append(i)
        if not pre:
            queue.append(i)
    while queue:
        i = queue.pop()
        for x in ops[i].effect_literals():  # conditional effects optimistically
            if x in reached or holds(x, init):
                continue
            reached.add(x)
            for j in waiting.get(x, ()):
                missing_count[j] -= 1
                if missing_count[j] == 0:
                    queue.append(j)
    return [x for x in goal if x not in reached]


def validate(
    task: Task, init: int, goal: tuple[int, ...], ops: list[GroundOp], planner: str
) -> None:
    s = init
    for k, op in enumerate(ops):
        if not op.applicable(s):
            raise DxboardError(f"planner {planner}: step {k} {op.label()} is not applicable")
        s = op.apply(s)
    bad = [task.describe(x) for x in goal if not holds(x, s)]
    if bad:
        raise DxboardError(f"planner {planner}: the plan leaves {', '.join(bad[:5])} unmet")
