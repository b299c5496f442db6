"""Search algorithms for subset-minimal diagnoses, behind a name -> callable registry.

A diagnosis (Reiter) is a set ``D`` of components such that ``SD + OBS + {AB(c) | c ∈ D} +
{¬AB(c) | c ∉ D}`` is consistent; we want the subset-minimal ones, by cardinality. Every
algorithm takes a ``SatContext``, the observation assumptions, the bounds and a ``Quota``
(quota.py: when enough of the most probable were found), and returns ``SearchOutcome`` (the
bad sets as component indexes, the bound that cut the list, and whether any diagnosis exists
at all). All find diagnoses by non-decreasing size; the diagnoser ranks them by probability.

- ``cardinality``: level 1 as a hitting-set step on the first conflict (``_singles``), then
  for k = 2, ... (from a lower bound: disjoint conflicts, or, for a minimal-cardinality
  request, RC2's minimum) ask the solver for a model with at most k
  abnormal components (totalizer bound as an assumption) that is no superset of a diagnosis
  found before (blocking clauses under the run's activation literal). Every model found at
  level k is a subset-minimal diagnosis of size k, for general clauses too (no monotonicity
  needed, since a model fixes every health variable).
- ``maxsat``: core-guided MaxSAT (PySAT's RC2: hard = clauses + observations, soft = each
  component healthy, weight 1); each optimum is a minimum-cardinality diagnosis, blocked as in
  ``cardinality`` before the next. Rebuilt per run (observations are hard clauses), so it
  suits one-shot diagnosis of hard instances, where cores find the lower bound fast.
- ``hitting-set``: conflict-directed, as in Reiter's theory but with an implicit hitting-set
  solver (PySAT's ``Hitman``, MaxSAT-based, minimal sets in order of size): check a candidate
  with all other components assumed healthy; an unsatisfiable core over those assumptions is a
  new conflict. Suits models with few, small conflicts.

- ``top-level`` (minimal-cardinality requests; others go to ``cardinality``): when the theory
  has circuit structure (``structure.infer_structure``: weak fault model, acyclic, total
  component behaviours), every minimal-cardinality diagnosis maps onto one of *top-level*
  components (not dominated on their way to the observed atoms): RC2 enumerates those,
  nearest the wrong outputs first, and each is expanded through the regions its components
  stand for (``toplevel.py``). Without structure, RC2 runs over all components. Each call
  builds its RC2 afresh (observations are hard clauses); the budget interrupts it.
- ``auto`` (default): ``cardinality``, except minimal-cardinality requests on models of at
  least ``AUTO_FROM`` (500) components whose level 1 is empty: those go on with
  ``top-level`` when at least ``TOP_LEVEL_DIRECT`` (1000) components are top-level or when
  more than one diagnosis of a circuit is wanted, else with ``cardinality`` (its minimum
  from RC2 over every component). Measured on ISCAS-85
  (benchmarks/RESULTS.md): level 1 (a few propagations) answers most single faults on every
  circuit; above it ``cardinality``'s RC2 is the faster one except where the reduction
  leaves a big search (c6288, minimum cardinality 4-5: RC2 over every gate 0.4-1 s, seconds
  for ``cardinality``'s totalizer). Robot-model re-diagnosis (no ``min_card_only``) is plain
  ``cardinality``.

All are cross-checked against brute force in ``tests/diagnosis``.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable

from host.diagnosis.quota import Quota
from host.diagnosis.result import Bound, SearchOutcome
from host.diagnosis.satctx import SatContext, maxsat_formula
from host.diagnosis.toplevel import min_card_search, top_level_count

Search = Callable[[SatContext, list[int], int | None, Quota, bool], SearchOutcome]
#: more diagnoses of the same size known without the solver, given one it found
#: (plan diagnosis: the same event in another gap, checked by simulation)
Expand = Callable[[frozenset[int]], Iterable[frozenset[int]]]
#: the levels above 1 of a minimal-cardinality request by another search (None: not taken)
BeyondOne = Callable[[SatContext, list[int], int | None, Quota], SearchOutcome | None]


def cardinality_search(
    ctx: SatContext,
    obs: list[int],
    max_card: int | None,
    quota: Quota,
    min_card_only: bool = False,
    expand: Expand | None = None,
    beyond_one: BeyondOne | None = None,
) -> SearchOutcome:
    """``beyond_one``: for a minimal-cardinality request whose level 1 is empty, the rest
    by another search (``auto``), or None to go on here."""
    n = len(ctx.ab_vars)
    act = ctx.new_run()
    base = [*obs, act]
    out = SearchOutcome([])
    try:
        limit = n if max_card is None else min(max_card, n)
        conflicts: list[set[int]] = []  # pairwise disjoint (the lower bound's)
        known: list[set[int]] = []  # every conflict found (``_left`` reads them)
        left: bool | None = None  # a diagnosis no superset of one found is known to exist
        # level 1 as a hitting-set step on the first conflict; the lower bound (more disjoint
        # conflicts) only when it found no single diagnosis: a small first conflict answers
        # k = 1 in a few propagations where the bound costs calls of its own
        quick = expand is None and limit >= 1
        k = _disjoint_cores(ctx, obs if quick else base, conflicts, quick, plain=quick)
        if _settled(out, k):  # out of time, or a conflict of no component: no diagnosis
            return out
        assert k is not None
        while k <= limit:
            if k == 1 and quick:
                known += conflicts
                two = (beyond_one is not None and limit >= 2
                       and _disjoint_cores(ctx, obs, conflicts, True, plain=True))
                if _settled(out, two):
                    return out
                if two == 2:  # two disjoint conflicts: no single diagnosis (big models: one
                    known.append(conflicts[-1])  # call instead of the candidates' checks)
                    listed = True
                else:
                    listed = _singles(ctx, obs, act, out, quota, conflicts[0], known)
                if listed and not out.bad_sets and beyond_one is not None and limit >= 2:
                    other = beyond_one(ctx, obs, max_card, quota)
                    if other is not None:  # the levels above 1 by another algorithm
                        return other
                if listed and not out.bad_sets:  # no single one: bound the size from here
                    # (up to 1 only: is there a diagnosis at all? one call, not the bound's)
                    seed: list[frozenset[int]] = []
                    bound = (_any(ctx, obs) if limit < 2
                             else _min_card(ctx, obs, seed) if min_card_only
                             else _disjoint_cores(ctx, obs, conflicts, plain=True))
                    if _settled(out, bound):
                        return out
                    assert bound is not None
                    k = max(bound, 2)
                    left = True  # the bound's last call was satisfiable, nothing blocked yet
                    if seed and k <= limit:  # RC2's optimum: a diagnosis of that level
                        out.bad_sets.append(seed[0])
                        quota.add(seed[0])
                        ctx.solver.add_clause([-ctx.ab_vars[i] for i in seed[0]] + [-act])
                        left = None
                    continue
            else:
                if quota.reached(k):  # e.g. RC2's optimum was the one wanted: no totalizer
                    out.cut_by = Bound.MAX_COUNT  # (c7552: building it cost more than RC2)
                    return out
                listed = ctx.list_diagnoses(base + ctx.at_most(k), act, out, quota, k, expand)
            if not listed:
                return out
            k += 1
            if min_card_only and out.bad_sets:
                return out
            left = None
            if k <= limit:  # anything left at all? (saves the levels above the last one)
                r = _left(ctx, obs, base, out, quick, known)
                if r is None:
                    out.cut_by = Bound.TIME_BUDGET
                    return out
                if not r:
                    return out
        if limit < n:
            r = left if left is not None else _left(ctx, obs, base, out, quick, known)
            if r is None or r:
                out.cut_by = Bound.TIME_BUDGET if r is None else Bound.MAX_CARD
        return out
    finally:
        ctx.end_run(act)


def _settled(out: SearchOutcome, bound: int | None) -> bool:
    """A lower bound's answer ends the search: None, out of time (``out`` says so); below 0,
    no diagnosis at all (a conflict of no component)."""
    if bound is None:
        out.cut_by = Bound.TIME_BUDGET
        return True
    if bound < 0:
        out.explainable = False
        return True
    return False


def _min_card(ctx: SatContext, obs: list[int], seed: list[frozenset[int]]) -> int | None:
    """The minimum cardinality by core-guided MaxSAT (RC2 on the theory and the
    observations; -1: no diagnosis; None: out of time): for a minimal-cardinality request
    whose level 1 is empty, the levels below the minimum are skipped without the totalizer
    bound's proofs that they are empty (c880, minimum 5: 180 ms against RC2's 4 ms). RC2's
    optimum, a diagnosis of minimum cardinality, is appended to ``seed`` (a request for one
    then needs no other call)."""
    if ctx.out_of_time():
        return None
    from pysat.examples.rc2 import RC2  # type: ignore[import-untyped]  # ~4 ms: only here

    with RC2(ctx.health_wcnf(), solver="g3") as rc2, ctx.interrupting(rc2):
        for lit in obs:  # hard: the formula, kept by the context, is not copied per request
            rc2.add_clause([lit])
        ctx.calls += 1
        found = rc2.compute_()
        if not found:
            return None if rc2.interrupted else -1
        model = rc2.oracle.get_model()  # read off the oracle: ``compute`` rebuilds it all
        seed.append(frozenset(i for i, v in enumerate(ctx.ab_vars)
                              if model[rc2.vmap.e2i[v] - 1] > 0))
        return max(int(rc2.cost), 2)


def _any(ctx: SatContext, obs: list[int]) -> int | None:
    """2 when some diagnosis exists (of 2 or more components, level 1 having found none),
    -1 when none does, None when out of time: ``_disjoint_cores``' answers, in one call."""
    r = ctx.solve_plain(obs)
    return None if r is None else 2 if r else -1


def _left(ctx: SatContext, obs: list[int], base: list[int], out: SearchOutcome,
          plain: bool, known: list[set[int]]) -> bool | None:
    """Is there a diagnosis that is no superset of one found (None: out of time)? While
    every one found is of one component (level 1), no when a conflict found lies within them
    (every diagnosis holds one of its components), else they are healthy assumptions on the
    theory alone (``solve_plain``) instead of blocking clauses on the run's solver."""
    if plain and all(len(b) == 1 for b in out.bad_sets):
        singles = {i for b in out.bad_sets for i in b}
        if any(c <= singles for c in known):
            return False
        return ctx.solve_plain(obs + [-ctx.ab_vars[i] for i in singles])
    return ctx.solve(base)


def _singles(ctx: SatContext, obs: list[int], act: int, out: SearchOutcome, quota: Quota,
             conflict: set[int], known: list[set[int]]) -> bool:
    """Level 1 as an HS-DAG does it: a one-component diagnosis lies in every conflict, so
    only the first conflict's components are candidates, each checked with every other
    component assumed healthy (unit propagation mostly; the totalizer bound's search is far
    slower at this level: c880 5x); a check that fails gives a conflict (its core) without
    the candidate, and a candidate outside a conflict found so is no diagnosis without a
    call (Reiter's label reuse). Found ones are blocked for the run as ``list_diagnoses``
    blocks them; the conflicts found are appended to ``known``. False when a bound (count,
    time) cut the listing. The checks run on the theory alone (``solve_plain``: the blocking
    clauses are satisfied by the assumptions)."""
    healthy = [-v for v in ctx.ab_vars]
    for i in sorted(conflict):
        if quota.reached(1):
            out.cut_by = Bound.MAX_COUNT
            return False
        if any(i not in c for c in known):
            continue
        r = ctx.solve_plain(obs + healthy[:i] + healthy[i + 1 :])
        if r is None:
            out.cut_by = Bound.TIME_BUDGET
            return False
        if r:
            bad = frozenset((i,))
            out.bad_sets.append(bad)
            quota.add(bad)
            ctx.solver.add_clause([-ctx.ab_vars[i], -act])
        else:
            known.append(_conflict(ctx))
    return True


def _conflict(ctx: SatContext) -> set[int]:
    """The components of the last unsatisfiable call's core (the health assumptions in it;
    the health variables are 1..n, ``SatContext``)."""
    n = len(ctx.ab_vars)
    return {-lit - 1 for lit in ctx.core() if 0 < -lit <= n}


def _disjoint_cores(ctx: SatContext, base: list[int], conflicts: list[set[int]],
                    first_only: bool = False, plain: bool = False) -> int | None:
    """A lower bound on the size of any diagnosis: the number of pairwise disjoint conflicts
    (each diagnosis holds a component of each), found from unsatisfiable cores with the
    conflicts' components left free, going on from those in ``conflicts`` (pairwise disjoint;
    the new ones are appended). ``first_only``: stop after one new conflict; ``plain``: on
    the theory alone (``solve_plain``; ``base`` names no run's variable). None when the
    time budget ran out, -1 when the observations contradict the model whatever is broken
    (an empty conflict: no diagnosis exists)."""
    free: set[int] = set().union(*conflicts)
    bound = len(conflicts)
    while True:
        assumptions = base + [-v for i, v in enumerate(ctx.ab_vars) if i not in free]
        r = ctx.solve_plain(assumptions) if plain else ctx.solve(assumptions)
        if r is None:
            return None
        if r:
            return bound
        conflict = _conflict(ctx)
        if not conflict:
            return -1
        free |= conflict
        bound += 1
        conflicts.append(conflict)
        if first_only:
            return bound


def maxsat_search(
    ctx: SatContext,
    obs: list[int],
    max_card: int | None,
    quota: Quota,
    min_card_only: bool = False,
) -> SearchOutcome:
    out = SearchOutcome([])
    wcnf = maxsat_formula([*ctx.encoding.clauses, *([lit] for lit in obs)],
                          [-v for v in ctx.ab_vars], max([len(ctx.encoding.vars), *map(abs, obs)]))
    n = len(ctx.ab_vars)
    from pysat.examples.rc2 import RC2  # ~4 ms: only here

    with RC2(wcnf, solver="g3", adapt=True, exhaust=True, minz=True, trim=5) as rc2:
        while True:
            if quota.reached(len(out.bad_sets[-1]) if out.bad_sets else 0):
                out.cut_by = Bound.MAX_COUNT
                return out
            if ctx.out_of_time():
                out.cut_by = Bound.TIME_BUDGET
                return out
            ctx.calls += 1
            model = rc2.compute()
            if model is None:
                out.explainable = bool(out.bad_sets)
                return out
            if min_card_only and out.bad_sets and rc2.cost > len(out.bad_sets[0]):
                return out
            if max_card is not None and rc2.cost > max_card:
                out.cut_by = Bound.MAX_CARD
                return out
            bad = frozenset(i for i, x in enumerate(model[:n]) if x > 0)
            out.bad_sets.append(bad)
            quota.add(bad)
            rc2.add_clause([-ctx.ab_vars[i] for i in bad])


def hitting_set_search(
    ctx: SatContext,
    obs: list[int],
    max_card: int | None,
    quota: Quota,
    min_card_only: bool = False,
) -> SearchOutcome:
    # imported here: only this algorithm uses it (with its LBX/MCSls, ~3 ms of every start)
    from pysat.examples.hitman import Hitman  # type: ignore[import-untyped]

    out = SearchOutcome([])
    healthy = [-v for v in ctx.ab_vars]
    hitman = Hitman(solver="g3", htype="sorted")
    size = 0  # the candidates come by non-decreasing size
    try:
        while True:
            if quota.reached(size):
                out.cut_by = Bound.MAX_COUNT
                return out
            if ctx.out_of_time():
                out.cut_by = Bound.TIME_BUDGET
                return out
            hs = hitman.get()
            if hs is None:
                return out
            cand = frozenset(int(i) for i in hs)
            size = len(cand)
            if min_card_only and out.bad_sets and len(cand) > len(out.bad_sets[0]):
                return out
            r = ctx.solve(obs + [h for i, h in enumerate(healthy) if i not in cand])
            if r is None:
                out.cut_by = Bound.TIME_BUDGET
                return out
            if r:
                if max_card is not None and len(cand) > max_card:
                    out.cut_by = Bound.MAX_CARD
                    return out
                out.bad_sets.append(cand)
                quota.add(cand)
                hitman.block(list(cand))
                continue
            conflict = [ctx.index_of_ab[-lit] for lit in ctx.core() if -lit in ctx.index_of_ab]
            if not conflict:
                out.explainable = False
                return out
            hitman.hit(conflict)
    finally:
        hitman.delete()


def top_level_search(
    ctx: SatContext,
    obs: list[int],
    max_card: int | None,
    quota: Quota,
    min_card_only: bool = False,
) -> SearchOutcome:
    """Minimal-cardinality diagnoses over the circuit's top-level components
    (``toplevel.py``); other requests go to ``cardinality_search``."""
    if not min_card_only:
        return cardinality_search(ctx, obs, max_card, quota, min_card_only)
    return min_card_search(ctx, obs, max_card, quota)


#: ``auto``: from this many components, a minimal-cardinality request whose level 1 is empty
#: goes on with ``top-level`` when at least ``TOP_LEVEL_DIRECT`` components are top-level
#: (the reduction left a big search, as on the c6288 multiplier), else with ``cardinality``.
AUTO_FROM = 500
TOP_LEVEL_DIRECT = 1000


def _top_level_beyond_one(ctx: SatContext, obs: list[int], max_card: int | None,
                          quota: Quota) -> SearchOutcome | None:
    """``auto``'s levels above 1 on big models: ``top-level`` when the top level is big, or
    when more than one diagnosis is wanted of a circuit (its RC2 lists the level from its
    cores: c7552, up to 1,000, 1.0 s against the totalizer's 1.9 s); None: ``cardinality``
    goes on, its minimum, and for one diagnosis the diagnosis, from RC2 over every
    component (c7552: 2-3x faster than ``top-level``'s reduction for that one)."""
    if top_level_count(ctx, obs) < TOP_LEVEL_DIRECT and (
            quota.count == 1 or ctx.structure() is None):
        return None
    return min_card_search(ctx, obs, max_card, quota)


def auto_search(
    ctx: SatContext,
    obs: list[int],
    max_card: int | None,
    quota: Quota,
    min_card_only: bool = False,
) -> SearchOutcome:
    """``cardinality``; on models of at least ``AUTO_FROM`` components a minimal-cardinality
    request that level 1 does not answer goes on with ``top-level`` when the top level is
    big. No wall-clock slice decides: a loaded machine cut the old 20 ms slice of
    ``cardinality`` and ``top-level`` then redid the work from scratch (c2670, c7552)."""
    if not min_card_only or len(ctx.ab_vars) < AUTO_FROM:
        return cardinality_search(ctx, obs, max_card, quota, min_card_only)
    return cardinality_search(ctx, obs, max_card, quota, True,
                              beyond_one=_top_level_beyond_one)


ALGORITHMS: dict[str, Search] = {
    "auto": auto_search,
    "cardinality": cardinality_search,
    "hitting-set": hitting_set_search,
    "maxsat": maxsat_search,
    "top-level": top_level_search,
}
DEFAULT_ALGORITHM = "auto"
