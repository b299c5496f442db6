"""The ``Diagnoser``: a theory, the current observations and an incremental solver, as one value.

Build one per context (the robot's hardware/software model now; later one per layer of a
hierarchy, over any propositions)::

    d = Diagnoser(theory)   # or algorithm= "cardinality" | "top-level" | "maxsat" |
                            # "hitting-set"; the default "auto" picks by size (search.py);
                            # min_card_only=True: diagnose() lists the smallest size only
                            # encoding=: the theory's SAT encoding (encoding.py), if at hand
    d.observe("~on(jaguar)", now=12.5, source="hobs", validity=3.0)   # S ⊕ o
    d.expire(now=20.0)                           # silent observers' literals become unknown
    # lags={"ok(/map)": 6.0}: an observation judging a 6 s window is held back (unknown)
    # while something it depends on changed less than 6 s ago (lags.py)
    result = d.diagnose(max_card=5, max_count=100, time_budget_s=0.5)
    result.diagnoses[0].bad, result.complete, result.cut_by

``observe``/``retract``/``expire``/``drop_source`` change only the assumption set; the solver,
its learnt clauses and the cardinality encoding are kept, so re-diagnosis after one changed
observation costs a few solver calls. An observation about an atom the theory does not know
raises ``UnknownLiteral``. ``diagnose`` with unchanged observations and bounds returns the
previous result. ``close()`` (or ``with Diagnoser(...) as d``) frees the solver and stops the
budget watchdog thread.

The daemon shares one ``ObservationSet`` (``observations=``) between the diagnoser and the repair
executor and diagnoses in a worker thread: it passes ``diagnose(literals=...)`` a snapshot of
the set taken on its own thread, and the diagnoser brings its solver assumptions to exactly
those literals (``assume``) before it searches; it never touches the set itself then.
"""

from __future__ import annotations

import logging
import time
from collections.abc import Iterable, Mapping

from host.diagnosis.encoding import Encoding
from host.diagnosis.lags import depends_on, held_atoms
from host.diagnosis.logic import Literal, Theory
from host.diagnosis.observations import Observation, ObservationSet
from host.diagnosis.quota import Quota, upper_bounds
from host.diagnosis.result import Bound, DiagnosisResult, prior_weights, rank
from host.diagnosis.satctx import SatContext
from host.diagnosis.search import ALGORITHMS, DEFAULT_ALGORITHM

log = logging.getLogger(__name__)


class UnknownLiteral(ValueError):
    """An observation names an atom the model does not mention."""


class Diagnoser:
    def __init__(
        self, theory: Theory, algorithm: str = DEFAULT_ALGORITHM, solver: str = "g4",
        observations: ObservationSet | None = None,
        lags: Mapping[str, float] | None = None, min_card_only: bool = False,
        encoding: Encoding | None = None,
    ) -> None:
        if algorithm not in ALGORITHMS:
            raise ValueError(f"unknown algorithm {algorithm!r}; use one of {sorted(ALGORITHMS)}")
        self.theory = theory
        self.algorithm = algorithm
        self.min_card_only = min_card_only  # the default of diagnose(): for huge models
        self._search = ALGORITHMS[algorithm]
        self._ctx = SatContext(theory, solver, encoding)
        self._observable = theory.observable_atoms()
        self._priors = {c: theory.prior(c) for c in theory.components}
        self._universe = frozenset(theory.components)
        self._weights = prior_weights(self._priors)
        self._index_weights = [self._weights[1][c] for c in theory.components]
        self._ub = upper_bounds(self._index_weights)
        self._assumed: dict[str, int] = {}  # atom -> solver literal of the current observation
        self.observations = observations if observations is not None else ObservationSet()
        self._lags = {a: t for a, t in (lags or {}).items() if a in self._observable and t > 0}
        self._inputs = depends_on(theory, self._lags) if self._lags else {}
        self._now = 0.0  # the latest time seen (observations, expiry): what lags count from
        self._version = 0
        self._cache: tuple[tuple[object, ...], DiagnosisResult] | None = None

    # -- observations ----------------------------------------------------------------------
    def observe(
        self,
        obs: Observation | Literal | str,
        now: float = 0.0,
        source: str = "",
        validity: float | None = None,
    ) -> bool:
        """``S := S ⊕ o``; True when the literal set changed."""
        if isinstance(obs, str):
            obs = self.theory.parse(obs)
        if isinstance(obs, Literal):
            obs = Observation(obs, now, source, validity)
        if obs.literal.atom not in self._observable:
            raise UnknownLiteral(
                f"observation {obs.literal} names {obs.literal.atom}, which no clause mentions"
            )
        self._now = max(self._now, obs.time)
        changed = self.observations.add(obs)
        if changed:
            self._version += 1
            self._assumed[obs.literal.atom] = self._ctx.lit(obs.literal)
        return changed

    def retract(self, atom: str) -> bool:
        changed = self.observations.retract(atom)
        if changed:
            self._version += 1
            del self._assumed[atom]
        return changed

    def expire(self, now: float) -> list[Observation]:
        self._now = max(self._now, now)
        return self._forget(self.observations.expire(now))

    def drop_source(self, source: str) -> list[Observation]:
        return self._forget(self.observations.drop_source(source))

    def assume(self, literals: Iterable[Literal]) -> bool:
        """Make ``literals`` the observations the next diagnosis assumes, replacing the ones
        assumed now (a snapshot of a set kept elsewhere); True when that changed anything.
        ``UnknownLiteral`` if one names an atom no clause mentions (nothing changed then)."""
        want = {lit.atom: lit for lit in literals}
        for lit in want.values():
            if lit.atom not in self._observable:
                raise UnknownLiteral(
                    f"observation {lit} names {lit.atom}, which no clause mentions")
        changed = False
        for atom in [a for a in self._assumed if a not in want]:
            del self._assumed[atom]
            changed = True
        for atom, lit in want.items():
            solver_lit = self._ctx.lit(lit)
            if self._assumed.get(atom) != solver_lit:
                self._assumed[atom] = solver_lit
                changed = True
        self._version += changed
        return changed

    def _forget(self, gone: list[Observation]) -> list[Observation]:
        for o in gone:
            del self._assumed[o.literal.atom]
        self._version += bool(gone)
        return gone

    # -- diagnosis -------------------------------------------------------------------------
    def _observed_false(self, atom: str) -> bool:
        o = self.observations.get(atom)
        return o is not None and not o.literal.positive

    def diagnose(
        self,
        max_card: int | None = None,
        max_count: int | None = None,
        time_budget_s: float | None = None,
        min_card_only: bool | None = None,
        literals: Iterable[Literal] | None = None,
        now: float | None = None,
    ) -> DiagnosisResult:
        """The subset-minimal diagnoses, most probable first, within the bounds.

        ``max_count`` keeps the most probable ones (``quota.Quota``: exact, whatever order
        the algorithm finds them in). ``min_card_only`` stops after the smallest cardinality
        that has diagnoses (the minimal-cardinality diagnoses); ``complete`` then refers to
        that level. None: the diagnoser's own setting (``Diagnoser(..., min_card_only=)``),
        so a caller that never passes it (the daemon) can be given it at construction.
        ``literals``: diagnose these observations (``assume``) instead of the diagnoser's own
        set. ``now``: the caller's time, for the lags (the daemon's observations reach the set
        without ``observe``, so their times do not advance the diagnoser's own clock).
        """
        if literals is not None:
            self.assume(literals)
        if now is not None:
            self._now = max(self._now, now)
        if min_card_only is None:
            min_card_only = self.min_card_only
        held = (held_atoms(self._lags, self._inputs, self.observations.since, self._now,
                           self._observed_false) if self._lags else ())
        key = (self._version, max_card, max_count, time_budget_s, min_card_only, held)
        if self._cache is not None and self._cache[0] == key:
            return self._cache[1]
        start = time.perf_counter()
        self._ctx.renew()  # a run's variables stay in the solver: bounded by starting afresh
        calls = self._ctx.calls
        assumptions = [x for atom, x in self._assumed.items() if atom not in held]
        quota = Quota(max_count, self._index_weights, self._ub)
        self._ctx.start_budget(time_budget_s)
        try:
            outcome = self._search(self._ctx, assumptions, max_card, quota, min_card_only)
            if outcome.cut_by is Bound.MAX_COUNT and not min_card_only:
                outcome.cut_by = self._count_cut(assumptions, outcome.bad_sets, max_card)
        finally:
            self._ctx.stop_budget()
        comps = self.theory.components
        bad = [frozenset(comps[i] for i in s) for s in outcome.bad_sets]
        ranked = rank(bad, self._priors, self._universe, self._weights)
        cut_by = outcome.cut_by
        if max_count is not None and len(ranked) > max_count:
            ranked = rank([d.bad for d in ranked[:max_count]], self._priors, self._universe,
                          self._weights)  # probabilities over the diagnoses kept
            cut_by = cut_by or Bound.MAX_COUNT
        result = DiagnosisResult(
            diagnoses=ranked,
            complete=cut_by is None,
            cut_by=cut_by,
            explainable=outcome.explainable,
            elapsed_s=time.perf_counter() - start,
            stats={"sat_calls": self._ctx.calls - calls},
            held=held,
        )
        log.debug("diagnosis: %d diagnoses, complete=%s, %.3f ms", len(bad), result.complete,
                  result.elapsed_s * 1000)
        self._cache = (key, result)
        return result

    def _count_cut(self, assumptions: list[int], found: list[frozenset[int]],
                   max_card: int | None) -> Bound | None:
        """The count was reached: which bound, if any, left a diagnosis out."""
        within = [] if max_card is None else self._ctx.at_most(max_card)
        more = self._ctx.more_than(assumptions + within, found)
        if more is None:
            return Bound.TIME_BUDGET
        if more:
            return Bound.MAX_COUNT
        if within and self._ctx.more_than(assumptions, found):
            return Bound.MAX_CARD
        return None

    def close(self) -> None:
        self._ctx.close()

    def __enter__(self) -> Diagnoser:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()
