"""Layer 2, the executive: a mission action carried out by ticking its behaviour tree.

``Executive.execute(command, dispatch_id)`` takes a mission action (``navigate(corridor,
office, door_office)``), binds it to its ``Recipe``'s parameters (φ: the action's parameters
by position), builds the tree (``host.executive.trees``) and ticks it every ``tick_s`` on the
event loop until it succeeds or fails. Every status change of a node is emitted as a
``TreeChange`` (the tick trace, with what the node said: a guard's reason to hold), and the
tree's result as a ``LayerResult`` of layer 2:

- success: ⟨success, data⟩, the data of its skills (the world's state at the end), passed up for
  the mission layer to check against its knowledge base;
- failure: ⟨fail, Δ⟩ with the failed subtask — the last leaf that failed, after the retries and
  fallbacks were spent — and its own explanation below (a guard's: the quarantined component;
  a skill's: the component layer 0 blames, or the world).

A hold is not a failure: while a guard holds, the tree is RUNNING and the failure clock of the
action is the guard's ``max_hold_s``. Stopping the task halts the tree (its skills' goals are
canceled).
"""

from __future__ import annotations

import asyncio
import logging
from collections.abc import Callable, Mapping, Sequence

import py_trees
from py_trees.common import Status

from host.events import Event, LayerResult, TreeChange
from host.executive.nodes import Trace
from host.executive.trees import Recipe, TreeContext, build
from host.layers import EXECUTIVE, Command, Result
from host.skills import Layer0View, Skill

log = logging.getLogger(__name__)

TICK_S = 0.1


class Executive:
    level = EXECUTIVE

    def __init__(self, recipes: Mapping[str, Recipe], parameters: Mapping[str, Sequence[str]],
                 skills: Mapping[str, Skill], layer0: Layer0View, clock: Callable[[], float],
                 emit: Callable[[Event], None], *, tick_s: float = TICK_S,
                 max_hold_s: float = 120.0, flat: bool = False) -> None:
        self.recipes = recipes
        self.parameters = parameters  # action -> its parameter names (?from, ?to, ...)
        self.skills = skills
        self.layer0 = layer0
        self.clock = clock
        self.emit = emit
        self.tick_s = tick_s
        self.max_hold_s = max_hold_s
        self.flat = flat

    async def execute(self, command: Command, dispatch_id: str = "") -> Result:
        started = self.clock()
        recipe = self.recipes.get(command.name)
        if recipe is None:
            result = Result.fail(EXECUTIVE, f"no behaviour tree for {command.name}")
        else:
            result = await self._run(recipe, command, dispatch_id)
        self.emit(LayerResult(EXECUTIVE, command.name, command.args, result.success,
                              result.explanation, started, self.clock(), dispatch_id,
                              data=result.data))
        return result

    async def _run(self, recipe: Recipe, command: Command, dispatch_id: str) -> Result:
        params = dict(zip(self.parameters.get(command.name, ()), command.args, strict=False))
        trace = Trace()
        ctx = TreeContext(self.skills, self.layer0, self.clock, self.emit, trace, self.max_hold_s,
                      dispatch_id)
        root = build(recipe, params, ctx, flat=self.flat)
        tree = py_trees.trees.BehaviourTree(root)
        seen: dict[object, tuple[Status, str]] = {}
        tick = 0
        try:
            while True:
                tree.tick()
                tick += 1
                self._trace(root, seen, tick, dispatch_id)
                if root.status in (Status.SUCCESS, Status.FAILURE):
                    break
                await asyncio.sleep(self.tick_s)
        finally:
            if root.status == Status.RUNNING:
                tree.interrupt()
        if root.status == Status.SUCCESS:
            return Result.ok(trace.data())
        if not trace.failures:
            return Result.fail(EXECUTIVE, f"{command}: the tree failed without a reason")
        node, below = trace.failures[-1]
        tries = recipe.retries + 1 if not self.flat else 1
        return Result.fail(EXECUTIVE, f"{command}: subtask {node!r} failed"
                           + (f" ({tries} attempts)" if tries > 1 else ""),
                           below=below, data=trace.data())

    def _trace(self, root: py_trees.behaviour.Behaviour,
               seen: dict[object, tuple[Status, str]], tick: int, dispatch_id: str) -> None:
        for node in root.iterate():
            now = (node.status, node.feedback_message)
            before = seen.get(node.id)
            if before is not None and before[0] == now[0] and \
                    (now[0] != Status.RUNNING or before[1] == now[1]):
                continue
            if before is None and node.status == Status.INVALID:
                continue
            seen[node.id] = now
            self.emit(TreeChange(dispatch_id, node.name, str(node.status.value),
                                 "" if before is None else str(before[0].value), tick,
                                 node.feedback_message))
