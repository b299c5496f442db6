"""Diagnosis as the daemon runs it: on every change of the observation set, off the event loop.

``DiagnosisRunner(diagnoser, observations, emit)`` owns the diagnoser of the daemon's one
``ObservationSet``. ``poke()`` says the set changed; ``task()`` (the daemon runs it) diagnoses
after each poke, and at least every ``safety_tick_s`` (which also expires the literals whose
observers fell silent: each becomes unknown, emitted as an ``Observation`` with value None and
source ``expired``). ``run(trigger)`` diagnoses now and returns the result (the repair service's
"fresh diagnosis"). Runs are serialised; each takes a snapshot of the set's literals on the
loop's thread and searches in a worker thread, so a long diagnosis (a large model, a hard
observation set) never stalls the loop that reads the board link — the diagnoser's own time
budget bounds it as before. Every run emits ``DiagnosisRun`` (its cost); a run whose bad sets
differ from the last one's emits ``DiagnosisRecord`` and calls ``on_changed(result)``.
``fold_updates`` folds the observers' updates into the set, for the daemon and for
``dxboard record``/``replay``.
"""

from __future__ import annotations

import asyncio
import functools
import logging
import time
from collections.abc import Callable, Iterable, Set
from concurrent.futures import ThreadPoolExecutor
from typing import Protocol

from host.diagnosis.coverage import Coverage
from host.diagnosis.diagnoser import Diagnoser
from host.diagnosis.observations import Observation as Seen
from host.diagnosis.observations import ObservationSet
from host.diagnosis.result import DiagnosisResult
from host.events import DiagnosisRecord, DiagnosisRun, Event, Observation

log = logging.getLogger(__name__)


class Retracted(Protocol):
    """What ``fold_updates`` reads of a retraction (the observers' ``Retraction`` is one): the
    atom whose last word from ``source`` no longer holds. A protocol here, so that diagnosis,
    on the floor below the observers, does not import them."""

    @property
    def atom(self) -> str: ...

    @property
    def source(self) -> str: ...


def fold_updates(updates: Iterable[Seen | Retracted], observations: ObservationSet, known: Set[str],
                 emit: Callable[[Event], None]) -> bool:
    """Fold observers' updates into the set (``S ⊕ o``), emitting each change as an
    ``Observation`` event; literals of atoms not in ``known`` (the model) are ignored. True when
    the set's literals changed (then it needs a diagnosis)."""
    changed = False
    for u in updates:
        if isinstance(u, Seen):
            if u.literal.atom not in known:
                log.warning("observation %s is not in the model; ignored", u.literal)
                continue
            if observations.add(u):
                emit(Observation(u.literal.atom, u.literal.positive, u.source))
                changed = True
        elif observations.retract(u.atom):
            emit(Observation(u.atom, None, u.source))
            changed = True
    return changed


class DiagnosisRunner:
    def __init__(self, diagnoser: Diagnoser, observations: ObservationSet,
                 emit: Callable[[Event], None], *, clock: Callable[[], float] = time.monotonic,
                 on_changed: Callable[[DiagnosisResult], None] | None = None,
                 safety_tick_s: float = 2.0, max_card: int | None = None,
                 max_count: int | None = 20, time_budget_s: float | None = 0.5) -> None:
        self.diagnoser = diagnoser
        self.observations = observations
        self.emit = emit
        self.clock = clock
        self.on_changed = on_changed
        self.safety_tick_s = safety_tick_s
        self.bounds = {"max_card": max_card, "max_count": max_count,
                       "time_budget_s": time_budget_s}
        self.result: DiagnosisResult | None = None
        self.coverage = Coverage(diagnoser.theory)
        self.unknown: tuple[str, ...] = ()  # components whose observations expired
        self._poked = asyncio.Event()
        self._lock = asyncio.Lock()
        self._worker = ThreadPoolExecutor(1, thread_name_prefix="diagnosis")

    def poke(self) -> None:
        """The observation set changed: diagnose soon."""
        self._poked.set()

    async def task(self) -> None:
        """Diagnose on every poke, and at least every ``safety_tick_s``; runs until cancelled."""
        while True:
            trigger = "observation"
            try:  # asyncio.timeout, not wait_for: 3.11's wait_for can swallow a cancel
                async with asyncio.timeout(self.safety_tick_s):
                    await self._poked.wait()
            except TimeoutError:
                trigger = "safety tick"
            self._poked.clear()
            await self.run(trigger)

    async def run(self, trigger: str) -> DiagnosisResult:
        """One diagnosis of the set as it is now (after expiring what ran out)."""
        async with self._lock:
            for gone in self.observations.expire(self.clock()):
                self.emit(Observation(gone.literal.atom, None, "expired"))
            literals = self.observations.literals()  # the snapshot, on the loop's thread
            unknown = self.coverage.observe({lit.atom for lit in literals})
            t0 = time.perf_counter()
            result = await asyncio.get_running_loop().run_in_executor(
                self._worker, functools.partial(self.diagnoser.diagnose, literals=literals,
                                                now=self.clock(),
                                                **self.bounds))  # type: ignore[arg-type]
            elapsed = time.perf_counter() - t0
            self.emit(DiagnosisRun(elapsed, trigger))
            old, self.result = self.result, result
            old_unknown, self.unknown = self.unknown, unknown
            if old is None or old.bad_sets() != result.bad_sets() or old_unknown != unknown:
                self.emit(DiagnosisRecord.of(
                    result.bad_sets(), complete=result.complete, trigger=trigger,
                    elapsed_s=elapsed, probabilities=[d.probability for d in result.diagnoses],
                    unknown=unknown))
            changed = old is None or old.bad_sets() != result.bad_sets()
            if changed and self.on_changed is not None:
                self.on_changed(result)
            return result

    def close(self) -> None:
        self._worker.shutdown(wait=True)
        self.diagnoser.close()
