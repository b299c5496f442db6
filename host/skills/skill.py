"""Layer 1, the skills: a goal of the world's skill servers, monitored and explained.

A ``SkillSpec`` names a skill of the robot (``navigate``), the layer-0 components and topics it
needs, and its monitor's limits: ``timeout_s`` for the whole goal, ``stall_s`` without progress.
``Skill.execute(command)`` is the layer's decision making and execution (``host.layers.Layer``):

1. resource check: a needed component quarantined or held makes the skill *unavailable* at once
   (⟨fail, Δ⟩ naming it; no goal is sent);
2. the goal goes to the world; every feedback (progress, what the skill waits for, the world's
   state) is an observation passed up (``observe``), and the monitor watches progress and time;
3. the result is ⟨success, data⟩ with the world's final state, or ⟨fail, Δ⟩ where the skill's
   diagnoser explains it with layer 0's words: the needed components layer 0 blames now
   (diagnosed abnormal, quarantined or held: ``Layer0View``), else "a fact of the world" (a
   closed door, a victim out of view: nothing broken).

A stall is not a failure while layer 0 is repairing what the skill needs: the stall clock is
held then (the executive's guard decides whether to wait, ``host.executive``) — unless the skill
is ``flat`` (a system without the layers' hand-over, the baseline of ``dxboard experiment
mission-fault``), whose monitor aborts as soon as the skill has waited ``FLAT_WAIT_S`` for
its inputs (a navigation without laser scans), as a navigation stack without a layer below
that repairs would. Cancelling the
task (the executive halting the skill) cancels the goal in the world. Time comes from ``clock``.
"""

from __future__ import annotations

import asyncio
import contextlib
import logging
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

from host.layers import SKILLS, Command, LayerObservation, Result
from host.skills.client import WorldClient
from host.skills.layer0 import AvailState, Layer0View

log = logging.getLogger(__name__)

POLL_S = 0.25
FLAT_WAIT_S = 1.0  # the flat system aborts a skill whose inputs stopped this long


@dataclass(frozen=True)
class SkillSpec:
    name: str
    needs: tuple[str, ...]
    timeout_s: float = 120.0
    stall_s: float = 10.0


class Skill:
    level = SKILLS

    def __init__(self, spec: SkillSpec, world: WorldClient, layer0: Layer0View,
                 clock: Callable[[], float],
                 observe: Callable[[LayerObservation], None] | None = None,
                 flat: bool = False) -> None:
        self.spec = spec
        self.flat = flat
        self.world = world
        self.layer0 = layer0
        self.clock = clock
        self.observe = observe or (lambda o: None)

    async def execute(self, command: Command) -> Result:
        spec = self.spec
        avail = self.layer0.availability(spec.needs)
        if avail.state is AvailState.UNAVAILABLE:
            return Result.fail(SKILLS, f"{spec.name} is unavailable: {avail.why}",
                               avail.components)
        handle = await self.world.goal(spec.name, dict(command.params))
        t0 = last_t = self.clock()
        progress = 0.0
        waiting: list[str] = []
        waiting_since: float | None = None
        try:
            while True:
                msg = await handle.next(POLL_S)
                now = self.clock()
                if msg is not None and msg.get("event") == "feedback":
                    waiting = [str(w) for w in msg.get("waiting", [])]
                    if float(msg.get("progress", 0.0)) > progress:
                        progress, last_t = float(msg["progress"]), now
                    self.observe(LayerObservation(SKILLS, "feedback", {
                        "skill": spec.name, "progress": progress, "waiting": waiting,
                        "state": msg.get("state", {})}, source=spec.name))
                elif msg is not None and msg.get("event") == "result":
                    return self._result(msg, waiting)
                if not self.flat and self.layer0.availability(spec.needs).state is AvailState.HOLD:
                    last_t = now  # layer 0 is on it: not a stall of this skill
                waiting_since = (None if not waiting else
                                 now if waiting_since is None else waiting_since)
                if self.flat and waiting_since is not None and \
                        now - waiting_since > FLAT_WAIT_S:
                    await handle.cancel()
                    return self._failed(f"{spec.name} aborted at {progress:.0%}: its inputs "
                                        "stopped" + self._waiting(waiting))
                if now - last_t > spec.stall_s:
                    await handle.cancel()
                    return self._failed(f"{spec.name} stalled for {now - last_t:.0f} s at "
                                        f"{progress:.0%}" + self._waiting(waiting))
                if now - t0 > spec.timeout_s:
                    await handle.cancel()
                    return self._failed(f"{spec.name} timed out after {spec.timeout_s:g} s at "
                                        f"{progress:.0%}" + self._waiting(waiting))
        except asyncio.CancelledError:
            with contextlib.suppress(Exception):
                await handle.cancel()
            raise

    def _result(self, msg: dict[str, Any], waiting: list[str]) -> Result:
        data = {**dict(msg.get("data") or {}), "state": msg.get("state", {})}
        if msg.get("success"):
            return Result.ok(data)
        status = str(msg.get("status", "failed"))
        what = f"{self.spec.name} {status}: {msg.get('message') or 'no reason given'}"
        return self._failed(what + self._waiting(waiting), data)

    def _failed(self, what: str, data: dict[str, Any] | None = None) -> Result:
        """The skill's diagnoser: the needed components layer 0 blames, else the world."""
        blamed = self.layer0.explain(self.spec.needs)
        if not blamed:
            what += "; layer 0 finds every component it needs working"
        return Result.fail(SKILLS, what, blamed, data=data)

    @staticmethod
    def _waiting(waiting: list[str]) -> str:
        return f" (waiting: {', '.join(waiting)})" if waiting else ""
