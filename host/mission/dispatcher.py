"""The mission layer's dispatcher and monitor (ROSPlan-like; paper 001 §II-A, §III-C).

``Dispatcher.dispatch(step, n)`` carries out one scheduled action of the plan:

1. the KB before it is recorded and its start and over-all conditions are checked against the
   KB (``Dispatch`` event with each ``ConditionCheck``); if one does not hold the action is
   *refused* — a propagated fault: the world is not as the plan assumed — and nothing runs;
2. its start effects are applied (``KbChange``, source ``effect``), and the executive (layer 2)
   runs it (φ: ``Command(2, name, args)``); meanwhile the monitor senses the world every
   ``sense_s`` (ψ, ``host.mission.sensing``) and an over-all condition that stops holding halts
   the action at once (a critical alarm); atoms the running action itself changes are left to it;
3. on success its end conditions are checked and its end effects applied; then, success or
   not, the world is sensed and every observation that contradicts the KB overrides it
   (``KbChange``, source ``sensing``). A success whose effects the world does not show is not
   trusted: the outcome is ``SURPRISE`` (an expected effect not observed);
4. the result ⟨s, Δ⟩ of layer 3 is emitted with the KB after it (``LayerResult``).

Everything plan-execution diagnosis needs to replay the history is in those events: the ground
action and its arguments, the KB before, the checks and their outcome, start and end, the
result, the observations that overrode the KB, and the KB after.
"""

from __future__ import annotations

import asyncio
import contextlib
import logging
from collections.abc import Awaitable, Callable, Mapping
from dataclasses import dataclass
from enum import StrEnum
from typing import Any, Protocol

from host.events import Dispatch, Event, LayerResult
from host.layers import EXECUTIVE, MISSION, Command, Result
from host.mission.kb import KnowledgeBase
from host.mission.sensing import Sensing
from host.planning.temporal_pddl import Atom, Literal, spell
from host.planning.temporal_planner import Scheduled

log = logging.getLogger(__name__)

SENSE_S = 1.0


class DispatchOutcome(StrEnum):
    DONE = "done"
    REFUSED = "refused"
    FAILED = "failed"
    SURPRISE = "surprise"


@dataclass(frozen=True)
class Dispatched:
    outcome: DispatchOutcome
    result: Result
    dispatch_id: str
    alarm: tuple[Literal, ...] = ()  # what was observed that raised it (as sensed)
    halted: bool = False  # an over-all condition stopped holding: halted at once


class Executes(Protocol):
    async def execute(self, command: Command, dispatch_id: str = "") -> Result: ...


WorldState = Callable[[], Awaitable[Mapping[str, Any]]]


class Dispatcher:
    def __init__(self, kb: KnowledgeBase, executive: Executes, world_state: WorldState,
                 sensing: Sensing, emit: Callable[[Event], None],
                 clock: Callable[[], float], mission_id: str, sense_s: float = SENSE_S,
                 on_sensed: Callable[[list[Literal], str], None] | None = None) -> None:
        self.kb = kb
        self.executive = executive
        self.world_state = world_state
        self.sensing = sensing
        self.emit = emit
        self.clock = clock
        self.mission_id = mission_id
        self.sense_s = sense_s
        self.on_sensed = on_sensed  # every observation, for plan-execution diagnosis
        self.count = 0

    async def sense(self, data: Mapping[str, Any] | None = None, cause: str = "",
                    dispatch_id: str = "", leave: frozenset[Atom] = frozenset()
                    ) -> list[Literal]:
        """Observe the world; every literal that contradicts the KB overrides it. Returns the
        overriding literals."""
        try:
            state = await self.world_state()
        except Exception as exc:  # the world is gone: nothing observed
            log.warning("cannot sense the world: %s", exc)
            return []
        lits, new = self.sensing.observe(self.kb.objects, state, data)
        for obj, typ in new.items():
            self.kb.learn(obj, typ)
        if self.on_sensed is not None:
            self.on_sensed(lits, dispatch_id)
        differ = [(a, pos) for a, pos in lits
                  if (a in self.kb.atoms) != pos and a not in leave]
        self.kb.change(differ, "sensing", cause, dispatch_id)
        return differ

    async def dispatch(self, step: Scheduled, index: int) -> Dispatched:
        g = step.ground
        self.count += 1
        did = f"{self.mission_id}.{self.count}"
        call = str(g)
        checks = self.kb.check(g.cond["start"], "start") + self.kb.check(g.cond["over all"],
                                                                          "over all")
        ok = all(c.held for c in checks)
        self.emit(Dispatch(did, self.mission_id, index, g.name, g.args, self.kb.snapshot(),
                           tuple(checks), ok, self.clock()))
        started = self.clock()
        if not ok:
            bad = [("" if c.expected else "not ") + c.atom for c in checks if not c.held]
            result = Result.fail(MISSION, f"{call} refused: {', '.join(bad)} does not hold "
                                 "(the world is not as the plan assumed)")
            return self._end(DispatchOutcome.REFUSED, result, g, started, did)
        self.kb.change(g.eff["start"], "effect", f"start of {call}", did)
        own = frozenset(a for lits in g.eff.values() for a, _ in lits)
        run = asyncio.ensure_future(self.executive.execute(
            Command(EXECUTIVE, g.name, g.args), did))
        violated = await self._monitor(run, g.cond["over all"], own, call, did)
        if violated:
            result = Result.fail(MISSION, f"{call} halted: over-all condition "
                                 f"{', '.join(violated)} stopped holding")
            await self.sense(None, f"after {call}", did)
            lits = tuple((a, not pos) for a, pos in g.cond["over all"]
                         if spell(a) in {v.removeprefix("not ") for v in violated})
            return self._end(DispatchOutcome.FAILED, result, g, started, did, lits, halted=True)
        result = run.result()
        if not result.success:
            await self.sense(result.data, f"after {call} failed", did)
            return self._end(DispatchOutcome.FAILED,
                             Result.fail(MISSION, f"{call} failed", below=result),
                             g, started, did)
        unmet = [c for c in self.kb.check(g.cond["end"], "end") if not c.held]
        if unmet:
            await self.sense(result.data, f"after {call}", did)
            what = ", ".join(("" if c.expected else "not ") + c.atom for c in unmet)
            return self._end(DispatchOutcome.FAILED, Result.fail(
                MISSION, f"{call}: end condition {what} does not hold"), g, started, did)
        self.kb.change(g.eff["end"], "effect", f"end of {call}", did)
        overridden = await self.sense(result.data, f"after {call}", did)
        expected = {(a, pos) for a, pos in g.eff["end"]}
        missed = [(a, pos) for a, pos in overridden if (a, not pos) in expected]
        if missed:
            what = ", ".join(("" if pos else "not ") + spell(a) for a, pos in missed)
            return self._end(DispatchOutcome.SURPRISE, Result.fail(
                MISSION, f"{call} reported success but the world shows {what}",
                data=result.data), g, started, did, tuple(missed))
        return self._end(DispatchOutcome.DONE, Result.ok(result.data), g, started, did)

    async def _monitor(self, run: asyncio.Future[Result], over_all: tuple[Literal, ...],
                       own: frozenset[Atom], call: str, did: str) -> list[str]:
        """Wait for the action, sensing meanwhile; the over-all literals that stopped holding
        (the action halted then), or [] when it ended by itself."""
        try:
            while not run.done():
                await asyncio.wait([run], timeout=self.sense_s)
                if run.done():
                    break
                await self.sense(None, f"during {call}", did, leave=own)
                bad = [("" if pos else "not ") + spell(a) for a, pos in over_all
                       if (a in self.kb.atoms) != pos]
                if bad:
                    run.cancel()
                    with contextlib.suppress(asyncio.CancelledError):
                        await run
                    return bad
        except asyncio.CancelledError:
            run.cancel()
            raise
        return []

    def _end(self, outcome: DispatchOutcome, result: Result, g: Any, started: float,
             did: str, alarm: tuple[Literal, ...] = (), halted: bool = False) -> Dispatched:
        self.emit(LayerResult(MISSION, g.name, g.args, result.success, result.explanation,
                              started, self.clock(), did, self.kb.snapshot(), result.data))
        return Dispatched(outcome, result, did, alarm, halted)
