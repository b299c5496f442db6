"""The executive's behaviour-tree leaves (py_trees): a guard and a skill action, and their trace.

``Guard`` is re-checked on every tick (it precedes its action in a sequence without memory, the
reactive sequence of paper 001 §II-B): ``SUCCESS`` while the skill's needs are available
(``host.skills.Layer0View``), ``RUNNING`` — the tree *holds*, its action halted — while layer 0
is repairing one of them, and ``FAILURE`` when one is quarantined or held by a person, or the
hold lasted longer than ``max_hold_s``. ``SkillAction`` runs one layer-1 command: its skill's
``execute`` as an asyncio task started when the node starts, ``RUNNING`` until it returns,
then ``SUCCESS`` or ``FAILURE`` by its result; a node halted by its guard (or the tree) cancels
the task, which cancels the goal in the world.

Both write what they concluded into the shared ``Trace``: every failure with its result
⟨fail, Δ⟩, and the results of the skills, so that the tree's runner can say which subtask
failed and why. The clock is passed in.
"""

from __future__ import annotations

import asyncio
import logging
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import py_trees
from py_trees.common import Status

from host.errors import DxboardError
from host.events import Event, LayerResult
from host.layers import EXECUTIVE, SKILLS, Command, Result
from host.skills import AvailState, Layer0View, Skill

log = logging.getLogger(__name__)


@dataclass
class Trace:
    """What the leaves of one tree concluded, in order."""

    failures: list[tuple[str, Result]] = field(default_factory=list)
    results: list[tuple[str, Result]] = field(default_factory=list)
    holds: int = 0

    def data(self) -> dict[str, Any]:
        """The skills' data, later results over earlier ones (the world's latest state)."""
        out: dict[str, Any] = {}
        for _, r in self.results:
            out.update(r.data)
        return out


class Guard(py_trees.behaviour.Behaviour):
    def __init__(self, name: str, needs: tuple[str, ...], layer0: Layer0View,
                 clock: Callable[[], float], trace: Trace, max_hold_s: float) -> None:
        super().__init__(name)
        self.needs = needs
        self.layer0 = layer0
        self.clock = clock
        self.trace = trace
        self.max_hold_s = max_hold_s
        self.hold_since: float | None = None

    def initialise(self) -> None:
        self.hold_since = None

    def update(self) -> Status:
        avail = self.layer0.availability(self.needs)
        if avail.state is AvailState.OK:
            self.feedback_message = ""
            return Status.SUCCESS
        if avail.state is AvailState.UNAVAILABLE:
            return self._fail(avail.why, avail.components)
        now = self.clock()
        if self.hold_since is None:
            self.hold_since = now
            self.trace.holds += 1
        if now - self.hold_since > self.max_hold_s:
            return self._fail(f"held {now - self.hold_since:.0f} s, longer than "
                              f"{self.max_hold_s:g} s: {avail.why}", avail.components)
        self.feedback_message = f"holding: {avail.why}"
        return Status.RUNNING

    def _fail(self, why: str, components: tuple[str, ...]) -> Status:
        self.feedback_message = why
        self.trace.failures.append((self.name, Result.fail(EXECUTIVE, f"{self.name}: {why}",
                                                           components)))
        return Status.FAILURE


class SkillAction(py_trees.behaviour.Behaviour):
    def __init__(self, name: str, skill: Skill, command: Command, trace: Trace,
                 clock: Callable[[], float], emit: Callable[[Event], None],
                 dispatch_id: str = "") -> None:
        super().__init__(name)
        self.skill = skill
        self.command = command
        self.trace = trace
        self.clock = clock
        self.emit = emit
        self.dispatch_id = dispatch_id
        self.task: asyncio.Task[Result] | None = None
        self.started = 0.0

    def initialise(self) -> None:
        self.started = self.clock()
        self.task = asyncio.ensure_future(self.skill.execute(self.command))

    def update(self) -> Status:
        task = self.task
        if task is None or not task.done():
            return Status.RUNNING
        self.task = None
        try:
            result = task.result()
        except DxboardError as exc:  # the world is gone: the skill cannot say more
            result = Result.fail(SKILLS, f"{self.command.name}: {exc}")
        self.emit(LayerResult(SKILLS, self.command.name, self.command.args, result.success,
                              result.explanation, self.started, self.clock(),
                              self.dispatch_id, data=result.data))
        self.trace.results.append((self.name, result))
        if result.success:
            return Status.SUCCESS
        self.feedback_message = result.describe()
        self.trace.failures.append((self.name, result))
        return Status.FAILURE

    def terminate(self, new_status: Status) -> None:
        if self.task is not None and not self.task.done():
            self.task.cancel()
            self.task = None
