"""ISCAS-85 circuits for the diagnosis benchmark: parsing, the weak-fault-model theory,
simulation, seeded fault instances, and the plain RC2 reference.

The circuits are ``shared/data/iscas85/*.bench`` beside the checkout or a folder above it
(``DXBOARD_SHARED`` names another ``shared`` directory). Each gate is a component under the
weak fault model: ``AB(g) or out(g) = f(inputs)``. An *instance* simulates the circuit on
random inputs with 1-5 random gates' outputs flipped, kept only when an output differs, and
observes every primary input and output. The *reference* is PySAT's RC2 on the whole model
(hard: the clauses and the observations; soft: each gate healthy), first optimum, as an
independent MaxSAT solver would be used.
"""

from __future__ import annotations

import os
import random
import sys
import threading
import time
from dataclasses import dataclass
from pathlib import Path

from pysat.examples.rc2 import RC2  # type: ignore[import-untyped]
from pysat.formula import WCNF  # type: ignore[import-untyped]

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from host.diagnosis import Clause, Literal, Theory, ab  # noqa: E402

SHARED = Path(os.environ.get("DXBOARD_SHARED") or next(
    (p / "shared" for p in ROOT.parents if (p / "shared" / "data").is_dir()),
    ROOT.parent / "shared"))
ISCAS = SHARED / "data" / "iscas85"
CIRCUITS = ["c17", "c432", "c499", "c880", "c1355", "c1908", "c2670", "c3540", "c5315",
            "c6288", "c7552"]


# -- ISCAS-85 ----------------------------------------------------------------------------------
@dataclass
class Circuit:
    name: str
    inputs: list[str]
    outputs: list[str]
    gates: list[tuple[str, str, list[str]]]  # (output signal, type, inputs), topological


def parse_bench(path: Path) -> Circuit:
    inputs: list[str] = []
    outputs: list[str] = []
    defs: dict[str, tuple[str, list[str]]] = {}
    for raw in path.read_text().splitlines():
        line = raw.split("#", 1)[0].strip()
        if not line:
            continue
        if line.upper().startswith("INPUT("):
            inputs.append(line[6:-1].strip())
        elif line.upper().startswith("OUTPUT("):
            outputs.append(line[7:-1].strip())
        else:
            out, expr = (s.strip() for s in line.split("=", 1))
            gtype, args = expr.split("(", 1)
            gtype = gtype.strip().lower()
            gtype = "buf" if gtype in ("buff", "buf") else gtype
            defs[out] = (gtype, [a.strip() for a in args.rstrip(")").split(",")])
    order: list[tuple[str, str, list[str]]] = []
    done = set(inputs)
    pending = dict(defs)
    while pending:  # Kahn-style topological order
        ready = [o for o, (_, ins) in pending.items() if all(i in done for i in ins)]
        for o in ready:
            order.append((o, *pending.pop(o)))
            done.add(o)
    return Circuit(path.stem, inputs, outputs, order)


def _gate_clauses(out: str, gtype: str, ins: list[str]) -> list[list[Literal]]:
    """CNF of out = gtype(ins), without the AB guard."""
    def L(a: str, pos: bool = True) -> Literal:
        return Literal(a, pos)

    neg = gtype in ("nand", "nor", "not", "xnor")
    o = L(out, not neg)  # the literal meaning "the un-negated function is true"
    no = -o
    if gtype in ("and", "nand"):
        return [[no, L(i)] for i in ins] + [[o, *(L(i, False) for i in ins)]]
    if gtype in ("or", "nor"):
        return [[o, L(i, False)] for i in ins] + [[no, *(L(i) for i in ins)]]
    if gtype in ("buf", "not"):
        return [[no, L(ins[0])], [o, L(ins[0], False)]]
    if gtype in ("xor", "xnor"):
        cls: list[list[Literal]] = []
        acc = L(ins[0])
        for k, nxt in enumerate(ins[1:], start=1):
            res = o if k == len(ins) - 1 else L(f"{out}.x{k}")
            b = L(nxt)
            cls += [[-res, acc, b], [-res, -acc, -b], [res, -acc, b], [res, acc, -b]]
            acc = res
        return cls
    raise ValueError(f"gate type {gtype}")


def circuit_theory(c: Circuit) -> Theory:
    clauses = []
    for out, gtype, ins in c.gates:
        guard = Literal(ab(out))
        clauses += [Clause((guard, *cl)) for cl in _gate_clauses(out, gtype, ins)]
    return Theory(tuple(g[0] for g in c.gates), tuple(clauses))


def simulate(c: Circuit, inputs: dict[str, bool], flipped: set[str]) -> dict[str, bool]:
    v = dict(inputs)
    for out, gtype, ins in c.gates:
        xs = [v[i] for i in ins]
        if gtype in ("and", "nand"):
            r = all(xs)
        elif gtype in ("or", "nor"):
            r = any(xs)
        elif gtype in ("xor", "xnor"):
            r = sum(xs) % 2 == 1
        else:
            r = xs[0]
        if gtype in ("nand", "nor", "not", "xnor"):
            r = not r
        v[out] = r != (out in flipped)
    return v


def sample(c: Circuit, rng: random.Random, n: int) -> list[tuple[int, list[Literal]]]:
    """``n`` instances: (gates flipped, uniform in 1-5; the observations)."""
    gates = [g[0] for g in c.gates]
    out: list[tuple[int, list[Literal]]] = []
    while len(out) < n:
        flips = set(rng.sample(gates, min(rng.randint(1, 5), len(gates))))
        inputs = {i: rng.random() < 0.5 for i in c.inputs}
        healthy = simulate(c, inputs, set())
        faulty = simulate(c, inputs, flips)
        if all(healthy[o] == faulty[o] for o in c.outputs):
            continue
        obs = [Literal(i, faulty[i]) for i in c.inputs]
        obs += [Literal(o, faulty[o]) for o in dict.fromkeys(c.outputs)]
        out.append((len(flips), obs))
    return out


def rc2_reference(theory: Theory, obs: list[Literal], budget_s: float) -> tuple[float, int | None]:
    """Seconds to RC2's first optimum over the whole model, and the minimum cardinality
    (None when the budget ran out first)."""
    wcnf, _ = _wcnf(theory, obs)
    start = time.perf_counter()
    with RC2(wcnf, solver="g3") as rc2:
        timer = threading.Timer(budget_s, rc2.interrupt)
        timer.start()
        try:
            model = rc2.compute(expect_interrupt=True)
        finally:
            timer.cancel()
        cost = None if model is None else int(rc2.cost)
    return time.perf_counter() - start, cost


def _wcnf(theory: Theory, obs: list[Literal]) -> tuple[WCNF, list[int]]:
    """Hard: the clauses and the observations; soft: each component healthy (weight 1)."""
    ids: dict[str, int] = {}

    def lit(x: Literal) -> int:
        v = ids.setdefault(x.atom, len(ids) + 1)
        return v if x.positive else -v

    comps = [ids.setdefault(ab(c), len(ids) + 1) for c in theory.components]
    wcnf = WCNF()
    for clause in theory.clauses:
        wcnf.append([lit(x) for x in clause.lits])
    for o in obs:
        wcnf.append([lit(o)])
    for v in comps:
        wcnf.append([-v], weight=1)
    return wcnf, comps


def rc2_all(theory: Theory, obs: list[Literal], max_card: int,
            budget_s: float) -> tuple[set[frozenset[int]], bool]:
    """A live peer: every subset-minimal diagnosis up to ``max_card`` by RC2 enumeration
    (each optimum blocked for its supersets); (diagnoses as component indexes, complete)."""
    wcnf, comps = _wcnf(theory, obs)
    index = {v: i for i, v in enumerate(comps)}
    out: set[frozenset[int]] = set()
    deadline = time.perf_counter() + budget_s
    with RC2(wcnf, solver="g3", exhaust=True) as rc2:
        timer = threading.Timer(budget_s, rc2.interrupt)
        timer.start()
        try:
            while time.perf_counter() < deadline:
                model = rc2.compute(expect_interrupt=True)
                if model is None:
                    return out, not rc2.interrupted
                if rc2.cost > max_card:
                    return out, True
                bad = frozenset(index[x] for x in model if x > 0 and x in index)
                out.add(bad)
                rc2.add_clause([-comps[i] for i in bad])
        finally:
            timer.cancel()
    return out, False


def lbx_all(theory: Theory, obs: list[Literal], max_card: int,
            budget_s: float) -> tuple[set[frozenset[int]], bool]:
    """A live peer: PySAT's LBX enumerating the minimal correction subsets of "every
    component healthy" (= the subset-minimal diagnoses, in no order of size), keeping those
    up to ``max_card``; complete only when it enumerated them all within ``budget_s``."""
    from pysat.examples.lbx import LBX  # type: ignore[import-untyped]

    wcnf, comps = _wcnf(theory, obs)
    soft_of = {i + 1: i for i in range(len(comps))}  # LBX numbers soft clauses from 1
    out: set[frozenset[int]] = set()
    deadline = time.perf_counter() + budget_s
    with LBX(wcnf, use_cld=True, solver_name="g3") as lbx:
        for mcs in lbx.enumerate():
            lbx.block(mcs)
            if len(mcs) <= max_card:
                out.add(frozenset(soft_of[j] for j in mcs))
            if time.perf_counter() > deadline:
                return out, False
    return out, True
