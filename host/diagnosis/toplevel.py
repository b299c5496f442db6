"""Minimal-cardinality diagnoses of circuits: top-level components, then their regions.

When the theory has circuit structure (``structure.py``: weak fault model, acyclic, total
behaviours), every minimal-cardinality diagnosis ``D`` maps onto one of *top-level*
components of the same size, ``T = {owner(g) | g ∈ D}``, where ``owner(g)`` is the nearest
top-level dominator of ``g`` and ``g`` lies in its *region*. So the minimal-cardinality
diagnoses are found in two steps:

1. **The top-level ones, by core-guided MaxSAT** (PySAT's RC2 over Glucose 3, ``exhaust``):
   hard clauses = the theory, the observations, and every component outside the top level
   healthy; one soft clause per top-level component. Its first optimum gives the minimum
   cardinality ``k`` and a first diagnosis; the next ones of cost ``k`` (each found one
   blocked) the other top-level diagnoses: RC2 keeps its cores, so each costs one SAT call
   (the incremental solver's at-most-k search took ten times as long on c6288). The soft
   clauses come *nearest the discrepancies first*: sorted by how many wrong observed atoms
   (those a healthy circuit computes otherwise from the observed inputs, one solver call) a
   component can influence, then in topological order. That is the order RC2's solver meets
   the health assumptions in, and starting where the outputs are wrong finds the cores that
   matter first: on the hardest c6288 instances measured it was 3-15x faster than
   topological order alone (benchmarks/RESULTS.md).
2. **Their expansions**: for a top-level diagnosis ``T``, each choice of one component from
   the region of every ``h ∈ T`` is checked with one solver call with every health variable
   assumed (all but the chosen healthy): with all inputs observed that is propagation. When
   the choices are many (large regions) the solver enumerates the consistent ones instead
   (one abnormal per region, the rest healthy), skipping the others unseen. By the mapping
   above this finds every minimal-cardinality diagnosis, each once.

Without circuit structure every component is its own region and step 1 runs over all of them.
The budget interrupts RC2; ``quota`` (quota.py) says when enough were found.
"""

from __future__ import annotations

import itertools
import math
from typing import TYPE_CHECKING

from host.diagnosis.quota import Quota
from host.diagnosis.result import Bound, SearchOutcome
from host.diagnosis.satctx import SatContext, maxsat_formula
from host.diagnosis.structure import Structure

if TYPE_CHECKING:
    from pysat.examples.rc2 import RC2  # type: ignore[import-untyped]


def _regions(ctx: SatContext, obs: list[int]) -> dict[int, list[int]]:
    structure = ctx.structure()
    if structure is None:
        return {i: [i] for i in range(len(ctx.ab_vars))}
    return structure.regions({a for a in map(ctx.atom_of, obs) if a is not None})


def top_level_count(ctx: SatContext, obs: list[int]) -> int:
    """How many components are top-level under these observations (cached per observed
    set: cheap enough to decide by)."""
    return len(_regions(ctx, obs))


def top_level_order(ctx: SatContext, obs: list[int]) -> list[int]:
    """The top-level components under these observations (all components when the theory
    has no circuit structure), nearest the discrepancies first (module docstring)."""
    structure = ctx.structure()
    top = _regions(ctx, obs)
    if structure is None:
        return list(top)
    order = [c for c in structure.order if c in top]
    wrong = _wrong_atoms(ctx, obs, structure)
    if not wrong:
        return order
    reach = structure.reach(wrong)
    position = {c: i for i, c in enumerate(order)}
    return sorted(order, key=lambda c: (-reach[c], position[c]))


def _wrong_atoms(ctx: SatContext, obs: list[int], structure: Structure) -> set[str]:
    """The observed atoms a healthy circuit gets wrong: one solver call with every component
    healthy and only the circuit's inputs observed (empty when that is not decisive)."""
    inputs = [x for x in obs if not structure.writes(ctx.atom_of(x) or "")]
    if ctx.solve(inputs + [-v for v in ctx.ab_vars]) is not True:
        return set()
    model = ctx.solver.get_model()
    wrong = set()
    for x in obs:
        atom = ctx.atom_of(x)
        if atom is not None and structure.writes(atom) and (model[abs(x) - 1] > 0) != (x > 0):
            wrong.add(atom)
    return wrong


def min_card_search(ctx: SatContext, obs: list[int], max_card: int | None,
                    quota: Quota) -> SearchOutcome:
    """The minimal-cardinality diagnoses (module docstring)."""
    out = SearchOutcome([])
    order = top_level_order(ctx, obs)
    regions = _regions(ctx, obs)
    keep = set(order)
    hard = [*ctx.encoding.clauses, *([lit] for lit in obs),
            *([-v] for i, v in enumerate(ctx.ab_vars) if i not in keep)]
    wcnf = maxsat_formula(hard, [-ctx.ab_vars[i] for i in order],
                          max([len(ctx.encoding.vars), *map(abs, obs)]))
    if ctx.out_of_time():
        out.cut_by = Bound.TIME_BUDGET
        return out
    from pysat.examples.rc2 import RC2  # ~4 ms: only here

    with RC2(wcnf, solver="g3", exhaust=True) as rc2, ctx.interrupting(rc2):
        internal = [(i, rc2.vmap.e2i[ctx.ab_vars[i]]) for i in order]
        k: int | None = None
        while True:
            ctx.calls += 1
            found = rc2.compute_()  # RC2's loop without its model rebuild (see _top_set)
            if not found:
                if rc2.interrupted:
                    out.cut_by = Bound.TIME_BUDGET
                elif k is None:  # a diagnosis maps onto a top-level one: none at all
                    out.explainable = False
                return out
            if k is None:
                k = rc2.cost
                if max_card is not None and k > max_card:
                    out.cut_by = Bound.MAX_CARD
                    return out
            elif rc2.cost > k:
                return out
            top = _top_set(rc2, internal)
            if not _expand(ctx, obs, top, regions, out, quota, k):
                return out
            rc2.add_clause([-ctx.ab_vars[i] for i in top])


def _top_set(rc2: RC2, internal: list[tuple[int, int]]) -> list[int]:
    """The abnormal top-level components of RC2's current model, read off its SAT oracle
    (``internal``: each component with its health variable's number inside RC2).
    ``RC2.compute`` would map the whole model back to the formula's variables first, 30 ms a
    call on c6288, which dominated the enumeration."""
    model = rc2.oracle.get_model()
    return [i for i, v in internal if model[v - 1] > 0]


#: expansions of at most this many choices are checked one by one (each a propagation);
#: larger ones (regions of dozens of gates, as in c3540) are enumerated by the solver, which
#: skips the inconsistent choices without trying them
CHECK_EACH_UP_TO = 64


def _expand(ctx: SatContext, obs: list[int], top: list[int], regions: dict[int, list[int]],
            out: SearchOutcome, quota: Quota, k: int) -> bool:
    """Add every diagnosis made of one component from each region of ``top`` to ``out``;
    False when a bound (count, time) cut the listing."""
    if math.prod(len(regions[h]) for h in top) > CHECK_EACH_UP_TO:
        return _expand_by_solver(ctx, obs, top, regions, out, quota, k)
    healthy = [-v for v in ctx.ab_vars]
    for choice in itertools.product(*(regions[h] for h in top)):
        if quota.reached(k):
            out.cut_by = Bound.MAX_COUNT
            return False
        bad = frozenset(choice)
        if list(choice) != top:  # the top-level diagnosis itself is known to be one
            assumptions = list(healthy)
            for i in bad:
                assumptions[i] = ctx.ab_vars[i]
            r = ctx.solve(obs + assumptions)
            if r is None:
                out.cut_by = Bound.TIME_BUDGET
                return False
            if not r:
                continue
        out.bad_sets.append(bad)
        quota.add(bad)
    return True


def _expand_by_solver(ctx: SatContext, obs: list[int], top: list[int],
                      regions: dict[int, list[int]], out: SearchOutcome, quota: Quota,
                      k: int) -> bool:
    """``_expand`` by enumeration: at least one abnormal component in each region (so exactly
    one, with at most ``k`` abnormal), every other component healthy, each found choice
    blocked; all for this run only."""
    act = ctx.new_run()
    try:
        inside: set[int] = set()
        for h in top:
            ctx.solver.add_clause([ctx.ab_vars[g] for g in regions[h]] + [-act])
            inside.update(regions[h])
        assumptions = [*obs, act, *ctx.at_most(k)]
        assumptions += [-v for i, v in enumerate(ctx.ab_vars) if i not in inside]
        return ctx.list_diagnoses(assumptions, act, out, quota, k)
    finally:
        ctx.end_run(act)
