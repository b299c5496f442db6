"""The repair loop: diagnose -> choose -> plan -> execute, again until healthy, bounded.

``RepairLoop(planner, executor, diagnose)`` is what the daemon runs when a diagnosis names
abnormal components. ``diagnose`` is the daemon's: an async callable returning the current
diagnoses as ``Candidate`` values (bad set, probability) and the observed literals, from the
diagnoser the observer hub feeds. One round (``repair_once``):

1. diagnose; drop the quarantined and held components from every candidate (a person must
   clear them; their failure is known and reported, or a person is working on them) — nothing
   left: the round ends;
2. ``choose`` the diagnosis to repair and its plan (``host.repair.policy``), reported through
   ``on_plan`` (a ``PlanRecord`` for the journal);
3. ``executor.execute`` it: steps verified by fresh observations, attempts counted.

``run()`` repeats rounds until the diagnosis is empty (``HEALTHY``), only quarantined components
are left (``QUARANTINED``; ``HELD`` when they are all held, none quarantined), no plan exists
(``NO_PLAN``), the plan touches a quarantined component (``BLOCKED``) or ``max_rounds`` is
reached (``GAVE_UP``). Replanning after a failed step is just the next round, after
``retry_pause_s`` for fresh evidence: the new diagnosis reflects what the failed step left
behind. It can never loop for ever: every executed round
counts an attempt for each component it touches, the executor quarantines a component after
``max_attempts`` in its window, and ``max_rounds`` bounds the rest. A lock makes ``run`` single-
flight: two repairs never run at once (and the executor refuses overlapping repairs of one
component anyway).
"""

from __future__ import annotations

import asyncio
import itertools
import logging
from collections.abc import Awaitable, Callable, Sequence
from dataclasses import dataclass
from enum import StrEnum
from typing import TYPE_CHECKING

from host.events import PlanRecord
from host.planning.errors import NoPlanError
from host.repair.executor import ExecutionResult, Executor, Outcome, plan_record
from host.repair.policy import Candidate, Choice, choose

if TYPE_CHECKING:
    from host.diagnosis.logic import Literal
    from host.repair.planner import RepairPlanner

log = logging.getLogger(__name__)

Diagnose = Callable[[], Awaitable[tuple[Sequence[Candidate], Sequence["Literal"]]]]
DEFAULT_MAX_ROUNDS = 10
# after a failed round, time for fresh evidence (a board's own retry, a device booting, the
# observers' windows) before the next diagnosis: otherwise a round would replan on what the
# failed step left half-done and spend the component's attempts in milliseconds
DEFAULT_RETRY_PAUSE_S = 2.0


class LoopOutcome(StrEnum):
    HEALTHY = "healthy"
    QUARANTINED = "quarantined"  # only quarantined (or quarantined and held) are abnormal
    HELD = "held"  # only components a person (or the board's shedding) holds are abnormal
    NO_PLAN = "no-plan"
    BLOCKED = "blocked"
    GAVE_UP = "gave-up"


@dataclass(frozen=True)
class Round:
    """One round: what was chosen (None: nothing to repair) and how its execution went."""

    choice: Choice | None
    result: ExecutionResult | None
    note: str = ""
    no_plan: bool = False
    quarantined: frozenset[str] = frozenset()  # abnormal but quarantined: not repaired


@dataclass(frozen=True)
class LoopResult:
    outcome: LoopOutcome
    rounds: tuple[Round, ...]
    reason: str = ""


class RepairLoop:
    def __init__(self, planner: RepairPlanner, executor: Executor, diagnose: Diagnose, *,
                 max_rounds: int = DEFAULT_MAX_ROUNDS,
                 on_plan: Callable[[PlanRecord], None] | None = None,
                 retry_pause_s: float = DEFAULT_RETRY_PAUSE_S) -> None:
        self.planner = planner
        self.retry_pause_s = retry_pause_s
        self.executor = executor
        self.diagnose = diagnose
        self.max_rounds = max_rounds
        self.on_plan = on_plan
        self._lock = asyncio.Lock()
        self._ids = itertools.count(1)

    async def repair_once(self) -> Round:
        """Diagnose, choose, plan and execute once."""
        candidates, observations = await self.diagnose()
        quarantined = self.executor.quarantine.components | frozenset(self.executor.held)
        kept: list[Candidate] = []
        dropped: set[str] = set()
        for c in candidates:
            dropped |= c.bad & quarantined
            kept.append(Candidate(c.bad - quarantined, c.probability))
        try:
            choice = choose(self.planner, kept, observations)
        except NoPlanError as exc:
            return Round(None, None, f"no plan: {exc}", no_plan=True)
        if not choice.plan.steps:
            note = "nothing to repair"
            held = {c for c in dropped if c in self.executor.held}
            if dropped - held:
                note += f"; quarantined: {', '.join(sorted(dropped - held))}"
            if held:
                note += f"; held: {', '.join(sorted(held))}"
            return Round(choice if choice.bad else None, None, note,
                         quarantined=frozenset(dropped))
        plan_id = f"repair-{next(self._ids)}"
        if self.on_plan is not None:
            self.on_plan(plan_record(choice.plan, plan_id, choice.bad))
        log.info("repairing %s: %s (%s)", sorted(choice.bad), choice.plan, choice.strategy)
        result = await self.executor.execute(choice.plan, plan_id, choice.bad)
        return Round(choice, result, result.reason, quarantined=frozenset(dropped))

    async def run(self) -> LoopResult:
        """Rounds until healthy or nothing more can be done (see the module docstring)."""
        async with self._lock:
            rounds: list[Round] = []
            for _ in range(self.max_rounds):
                r = await self.repair_once()
                rounds.append(r)
                if r.result is None:
                    if r.no_plan:
                        return LoopResult(LoopOutcome.NO_PLAN, tuple(rounds), r.note)
                    if r.quarantined & self.executor.quarantine.components:
                        return LoopResult(LoopOutcome.QUARANTINED, tuple(rounds), r.note)
                    if r.quarantined:
                        return LoopResult(LoopOutcome.HELD, tuple(rounds), r.note)
                    return LoopResult(LoopOutcome.HEALTHY, tuple(rounds), r.note)
                if r.result.outcome is Outcome.BLOCKED:
                    return LoopResult(LoopOutcome.BLOCKED, tuple(rounds), r.result.reason)
                if self.executor.dry_run:  # nothing changed: the next round would repeat it
                    return LoopResult(LoopOutcome.GAVE_UP, tuple(rounds), "dry run: one round")
                if r.result.outcome is not Outcome.DONE:
                    await asyncio.sleep(self.retry_pause_s)
            return LoopResult(LoopOutcome.GAVE_UP, tuple(rounds),
                              f"still abnormal after {self.max_rounds} rounds")
