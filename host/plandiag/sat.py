"""The SAT encoding of a history: which variant ran at each step, which events in each gap.

One Boolean variable per fault (a fault mode at a step, an event in a gap) comes first, so the
faults play the part layer 0's health variables play and its searches run unchanged
(``host.diagnosis.search.cardinality_search``: level by level under an incremental totalizer
bound, each diagnosis blocked for its supersets, lower bound from disjoint cores, the time
budget enforced by interrupting the solver). The rest is the history as a planning-as-SAT
chain over the points of ``problem.py``:

- an atom gets a new variable only where something may change it (a step one of whose variants
  writes it, a gap with a candidate event that writes it); elsewhere it keeps its variable, or
  the constant it has from the initial state on. A step whose only variant is its nominal action
  adds no variable at all: its preconditions become unit clauses, its effects constants;
- a variant or event implies its precondition before and its effects after; the step's
  variants are exactly one (the nominal action's variable is not a fault);
- explanatory frame axioms: an atom that changes does so because a variant or event that
  writes it that way ran; two events of one gap never add and delete the same atom;
- observations are unit clauses at their points.

``order=probability`` enumerates with PySAT's RC2 instead (weighted MaxSAT, weight ``-log p``
per fault in millionths, which ranks by the product of the priors): each optimum, blocked in
turn, is a subset-minimal diagnosis, most probable first.
"""

from __future__ import annotations

import math
import time

from pysat.card import CardEnc, EncType  # type: ignore[import-untyped]
from pysat.formula import WCNF  # type: ignore[import-untyped]

from host.diagnosis.logic import Theory
from host.diagnosis.quota import Quota
from host.diagnosis.result import Bound
from host.diagnosis.satctx import SatContext
from host.diagnosis.search import cardinality_search
from host.plandiag.limits import Deadline, ExplainOutcome, Limits, Order
from host.plandiag.model import FaultKind
from host.plandiag.problem import (
    HistoryProblem,
    apply_events,
    bits,
    conflict,
    effective_delete,
    live_atoms,
    simulate,
    writes,
)
from host.planning.task import GroundOp

#: RC2's integer weights are ``-log p`` in millionths: histories whose priors differ by more
#: than a few parts in a million come in the right order (thousandths swapped close ones)
WEIGHT_SCALE = 1_000_000


class HistoryEncoding:
    """The clauses of one history over one universe of faults, in one ``SatContext``."""

    def __init__(self, problem: HistoryProblem, universe: frozenset[int] | None) -> None:
        self.p = problem
        allowed = (lambda f: True) if universe is None else universe.__contains__
        live = live_atoms(problem, allowed)
        ids = [f.id for f in problem.faults if allowed(f.id) and (
            f.kind is FaultKind.MODE or writes(f.op) & live[2 * f.at - 1])]
        self.fault_ids = ids
        self.ctx = SatContext(Theory(tuple(str(f) for f in ids), ()))
        self.fvar = dict(zip(ids, self.ctx.ab_vars, strict=True))
        self.index = {f: i for i, f in enumerate(ids)}  # fault id -> its health-variable index
        # an event's place in its gap's list (the same ground events in every gap), and
        # the places of the events each conflicts with (decided once for all gaps)
        self.event_slot = {f: j for gap in problem.gaps for j, f in enumerate(gap)}
        slots = [problem.faults[f].op for f in problem.gaps[0]] if problem.gaps else []
        self.conflicts = [[k for k in range(j + 1, len(slots)) if conflict(op, slots[k])]
                          for j, op in enumerate(slots)]
        self.hard: list[list[int]] = []
        self.true = self.ctx.new_var()
        self._add([self.true])
        n = len(problem.task.atoms)
        self.cur = [self.true if (problem.init >> a) & 1 else -self.true for a in range(n)]
        self._observe(0)
        for spec in problem.steps:
            self._gap(spec.index)
            self._observe(2 * spec.index - 1)
            if not spec.executed or 2 * spec.index - 1 >= problem.last_point:
                break
            self._step(spec.index)
            self._observe(2 * spec.index)
        self.ctx.solver.append_formula(self.hard)

    def _add(self, clause: list[int]) -> None:
        self.hard.append(clause)

    def _const(self, lit: int) -> bool | None:
        if lit == self.true:
            return True
        if lit == -self.true:
            return False
        return None

    def _observe(self, point: int) -> None:
        t, f = self.p.obs.get(point, (0, 0))
        for a in bits(t):
            self._add([self.cur[a]])
        for a in bits(f):
            self._add([-self.cur[a]])

    def _holds(self, guard: int, op: GroundOp) -> bool:
        """``guard -> pre(op)`` on the current variables; False when it can never hold."""
        clauses = []
        for x in op.pre:
            lit = self.cur[x >> 1] if x & 1 else -self.cur[x >> 1]
            c = self._const(lit)
            if c is False:
                return False
            if c is None:
                clauses.append([-guard, lit])
        for cl in clauses:
            self._add(cl)
        return True

    def _transition(self, variants: list[tuple[int, GroundOp]]) -> None:
        """Effects and frame axioms of the variants (guards) that may run here."""
        written = 0
        for _, op in variants:
            written |= op.add | op.delete
        nxt: dict[int, int] = {}
        for a in bits(written):
            nxt[a] = self.ctx.new_var()
        adders: dict[int, list[int]] = {a: [] for a in nxt}
        deleters: dict[int, list[int]] = {a: [] for a in nxt}
        for g, op in variants:
            for a in bits(op.add):
                self._add([-g, nxt[a]])
                adders[a].append(g)
            for a in bits(effective_delete(op)):
                self._add([-g, -nxt[a]])
                deleters[a].append(g)
        for a, v in nxt.items():
            old = self.cur[a]
            self._add([-old, v, *deleters[a]])
            self._add([old, -v, *adders[a]])
            self.cur[a] = v

    def _gap(self, gap: int) -> None:
        live: dict[int, tuple[int, GroundOp]] = {}  # slot -> (variable, event)
        for j, fid in enumerate(self.p.gaps[gap - 1]):
            v = self.fvar.get(fid)
            if v is None:
                continue
            op = self.p.faults[fid].op
            if self._holds(v, op):
                live[j] = (v, op)
            else:
                self._add([-v])
        for j, (v1, _) in live.items():
            for k in self.conflicts[j]:
                if k in live:
                    self._add([-v1, -live[k][0]])
        if live:
            self._transition(list(live.values()))

    def _step(self, index: int) -> None:
        spec = self.p.steps[index - 1]
        modes = [(self.fvar[f], self.p.faults[f].op) for f in spec.modes if f in self.fvar]
        if not modes:
            op = spec.nominal
            if op is None or not self._holds(self.true, op):
                self._add([-self.true])  # no variant can run here: no diagnosis at all
                return
            for a in bits(op.add):
                self.cur[a] = self.true
            for a in bits(effective_delete(op)):
                self.cur[a] = -self.true
            return
        variants: list[tuple[int, GroundOp]] = []
        if spec.nominal is not None:
            g = self.ctx.new_var()  # the nominal action ran: not a fault
            if self._holds(g, spec.nominal):
                variants.append((g, spec.nominal))
        for v, op in modes:
            if self._holds(v, op):
                variants.append((v, op))
            else:
                self._add([-v])
        guards = [g for g, _ in variants]
        self._add(guards)  # at least one (an empty clause when none can run)
        if len(guards) > 1:
            am1 = CardEnc.atmost(lits=guards, bound=1, top_id=self.ctx.top,
                                 encoding=EncType.seqcounter if len(guards) > 6
                                 else EncType.pairwise)
            self.ctx.top = max(self.ctx.top, am1.nv)
            for cl in am1.clauses:
                self._add(cl)
        self._transition(variants)

    # -- searches -------------------------------------------------------------------------
    def diagnoses(self, limits: Limits) -> ExplainOutcome:
        start = time.perf_counter()
        if limits.order is Order.PROBABILITY:
            out = self._by_probability(limits)
        else:
            self.ctx.start_budget(limits.time_budget_s)
            calls = self.ctx.calls
            try:
                # a plain count (every diagnosis weighs the same): stop at the (N+1)-th
                # found, so that the cut is reported only when it left one out
                n = limits.max_count
                quota = Quota(None if n is None else n + 1, [0.0] * len(self.ctx.ab_vars))
                found = cardinality_search(self.ctx, [], limits.max_card, quota,
                                           expand=self._siblings)
            finally:
                self.ctx.stop_budget()
            bad_sets = found.bad_sets
            cut_by = found.cut_by
            if n is not None and len(bad_sets) > n:
                bad_sets, cut_by = bad_sets[:n], Bound.MAX_COUNT
            out = ExplainOutcome([frozenset(self.fault_ids[i] for i in bad) for bad in bad_sets],
                          cut_by, self.ctx.calls - calls)
        out.elapsed_s = time.perf_counter() - start
        return out

    def _siblings(self, found: frozenset[int]) -> list[frozenset[int]]:
        """The same diagnosis with one of its events in another gap, where that is consistent
        too: an event nobody saw for a while may have happened in any gap of the while, and
        one solver call per gap would cost far more.

        An earlier gap is checked by simulation from there until the history rejoins the one
        found. For the later gaps one run without the event (from its gap on) serves them
        all: the event moved to gap ``g2`` sees that run's state before ``g2``, and if the
        state after ``g2`` is the found history's, the rest is too; once that run has
        contradicted an observation, the event moved any later contradicts it as well."""
        p = self.p
        d = frozenset(self.fault_ids[i] for i in found)
        ref = simulate(p, d)
        out: list[frozenset[int]] = []
        if not ref.consistent:  # pragma: no cover - the solver's model is a diagnosis
            return out
        events_in: dict[int, list[int]] = {}
        for f in d:
            if f in self.event_slot:
                events_in.setdefault(p.faults[f].at, []).append(f)
        for e in d:
            j = self.event_slot.get(e)
            if j is None:
                continue
            g = p.faults[e].at
            without = simulate(p, d - {e}, start=g, rejoin=ref.states, rejoin_at=len(ref.states))
            reach = len(ref.states) if without.consistent else without.stop_point
            for g2, gap in enumerate(p.gaps, start=1):
                other = gap[j]
                if g2 == g or other not in self.index or other in d:
                    continue
                if g2 > g and 2 * g2 - 1 > reach:
                    break  # a contradiction before g2 that only the event could mend
                if self.ctx.out_of_time():
                    return out
                moved = (d - {e}) | {other}
                if g2 > g:
                    before = without.states[2 * g2 - 2 - (2 * g - 2)]
                    ops = [p.faults[f].op for f in events_in.get(g2, ())] + [p.faults[other].op]
                    after = apply_events(before, ops)
                    if after is None:
                        continue
                    if after == ref.states[2 * g2 - 1]:
                        out.append(frozenset(self.index[f] for f in moved))
                        continue
                lo, hi = min(g, g2), max(g, g2)
                if simulate(p, moved, start=lo, rejoin=ref.states, rejoin_at=2 * hi - 1).consistent:
                    out.append(frozenset(self.index[f] for f in moved))
        return out

    def _by_probability(self, limits: Limits) -> ExplainOutcome:
        out = ExplainOutcome()
        wcnf = WCNF()
        for cl in self.hard:
            wcnf.append(cl)
        for fid, v in self.fvar.items():
            cost = -math.log(self.p.faults[fid].prior)
            wcnf.append([-v], weight=1 + round(WEIGHT_SCALE * cost))
        index = {v: fid for fid, v in self.fvar.items()}
        deadline = Deadline(limits.time_budget_s)
        self.ctx.start_budget(limits.time_budget_s)
        try:
            from pysat.examples.rc2 import RC2  # type: ignore[import-untyped]  # ~4 ms: only here

            with RC2(wcnf, solver="g3", exhaust=True) as rc2, self.ctx.interrupting(rc2):
                while True:
                    if deadline.passed():
                        out.cut_by = Bound.TIME_BUDGET
                        break
                    out.nodes += 1
                    model = rc2.compute(expect_interrupt=True)
                    if model is None:
                        if rc2.interrupted:
                            out.cut_by = Bound.TIME_BUDGET
                        break
                    bad = frozenset(index[x] for x in model if x > 0 and x in index)
                    if limits.max_card is not None and len(bad) > limits.max_card:
                        out.cut_by = Bound.MAX_CARD  # minimal but too big: skip it
                        rc2.add_clause([-self.fvar[f] for f in bad])
                        continue
                    if limits.max_count is not None and len(out.diagnoses) >= limits.max_count:
                        out.cut_by = Bound.MAX_COUNT  # one more exists: the cut left it out
                        break
                    out.diagnoses.append(bad)
                    rc2.add_clause([-self.fvar[f] for f in bad])
        finally:
            self.ctx.stop_budget()
        return out

    def close(self) -> None:
        self.ctx.close()


def any_beyond(problem: HistoryProblem, universe: frozenset[int] | None,
               found: list[frozenset[int]], budget_s: float | None) -> bool | None:
    """Is there a minimal diagnosis besides ``found``, of any size? One solver call: a
    consistent history that is no superset of one found holds such a diagnosis. The tree and
    naive ask it once they have listed every diagnosis up to ``max_card``, to know whether the
    bound left one out. None when ``budget_s`` ran out first."""
    enc = HistoryEncoding(problem, universe)
    try:
        for d in found:
            if all(f in enc.fvar for f in d):  # else not minimal here: blocks nothing more
                enc.ctx.solver.add_clause([-enc.fvar[f] for f in d])
        enc.ctx.start_budget(budget_s)
        try:
            return enc.ctx.solve([])
        finally:
            enc.ctx.stop_budget()
    finally:
        enc.close()


def sat_engine(problem: HistoryProblem, universe: frozenset[int] | None,
               limits: Limits) -> ExplainOutcome:
    enc = HistoryEncoding(problem, universe)
    try:
        return enc.diagnoses(limits)
    finally:
        enc.close()
