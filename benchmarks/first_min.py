"""First minimum-cardinality diagnosis against live MaxSAT peers, and multiple observations.

Issue 30 item 1 (first minimum cardinality): on a fresh seeded ISCAS-85 sample
(benchmarks/iscas.py), dxboard's first minimal-cardinality diagnosis (``min_card_only``,
``max_count`` 1, the default algorithm) against two MaxSAT solvers run here on the same
instances, each on the whole model (hard: clauses and observations; soft: each gate healthy;
the formula is built before the clock starts, the peer's solver inside it, since each
instance's observations are hard clauses there): PySAT's RC2 (core-guided) and LSU (linear
SAT-UNSAT search, model-improving). The minimum each finds must equal ours (asserted). Times
are this thread's CPU time (the searches are single-threaded; the machine is shared, so wall
time says more about the load than about the engine); the wall-clock budget cuts a run
(counted, left out of the mean).

Multiple observations (the kind of instance of Ignatiev, Morgado, Weissenbacher and
Marques-Silva, "Model-based diagnosis with multiple observations", IJCAI 2019; their files
cannot be fetched here, so the benchmark generates the same kind): one circuit with 1-5 gates
flipped, observed under ``m`` random input vectors (at least one showing a wrong output); a
diagnosis must be consistent with all of them. The theory holds one copy of every signal per
observation and one health variable per gate, shared.

    .venv/bin/python -m benchmarks.first_min [--circuits c432 c6288] [--per-circuit N]
        [--observations 2,4,8] [--budget S] [--seed N]
"""

from __future__ import annotations

import argparse
import os
import random
import statistics
import sys
import threading
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

from pysat.examples.lsu import LSU  # type: ignore[import-untyped]
from pysat.examples.rc2 import RC2  # type: ignore[import-untyped]
from pysat.formula import WCNF  # type: ignore[import-untyped]

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from benchmarks.iscas import (  # noqa: E402
    CIRCUITS,
    ISCAS,
    Circuit,
    _gate_clauses,
    _wcnf,
    circuit_theory,
    parse_bench,
    sample,
    simulate,
)
from host.diagnosis import Clause, Diagnoser, Literal, Theory, ab  # noqa: E402
from host.diagnosis.encoding import encode  # noqa: E402

CPU = time.thread_time


def rc2_first(wcnf: WCNF, budget_s: float) -> int | None:
    """RC2's first optimum (its cost: the minimum cardinality; None when cut)."""
    with RC2(wcnf, solver="g3") as rc2:
        timer = threading.Timer(budget_s, rc2.interrupt)
        timer.start()
        try:
            model = rc2.compute(expect_interrupt=True)
        finally:
            timer.cancel()
        return None if model is None or rc2.interrupted else int(rc2.cost)


def lsu_first(wcnf: WCNF, budget_s: float) -> int | None:
    """LSU's optimum (SAT-UNSAT: each model's cost bounded below itself until UNSAT)."""
    lsu = LSU(wcnf, solver="g4", expect_interrupt=True)
    timer = threading.Timer(budget_s, lsu.interrupt)
    timer.start()
    try:
        found = lsu.solve()
        return int(lsu.cost) if found and lsu.found_optimum() else None
    finally:
        timer.cancel()
        lsu.delete()


def ours_first(d: Diagnoser, budget_s: float) -> int | None:
    r = d.diagnose(min_card_only=True, max_count=1, time_budget_s=budget_s)
    return r.diagnoses[0].cardinality if r.diagnoses else None  # by size: the first is minimum


def cpu_run(fn: Callable[..., int | None], *args: Any) -> tuple[float, int | None]:
    c = CPU()
    k = fn(*args)
    return CPU() - c, k


# -- multiple observations -----------------------------------------------------------------------
def multi_theory(c: Circuit, m: int) -> Theory:
    """Gates as components, ``m`` copies of every signal (``s@j``), the health shared."""
    clauses = []
    for j in range(m):
        for out, gtype, ins in c.gates:
            guard = Literal(ab(out))
            for cl in _gate_clauses(f"{out}@{j}", gtype, [f"{i}@{j}" for i in ins]):
                clauses.append(Clause((guard, *cl)))
    return Theory(tuple(g[0] for g in c.gates), tuple(clauses))


def multi_sample(c: Circuit, rng: random.Random, n: int, m: int) -> list[list[Literal]]:
    """``n`` instances: 1-5 gates flipped, ``m`` input vectors, one at least showing it."""
    gates = [g[0] for g in c.gates]
    out: list[list[Literal]] = []
    while len(out) < n:
        flips = set(rng.sample(gates, min(rng.randint(1, 5), len(gates))))
        obs: list[Literal] = []
        wrong = False
        for j in range(m):
            inputs = {i: rng.random() < 0.5 for i in c.inputs}
            healthy = simulate(c, inputs, set())
            faulty = simulate(c, inputs, flips)
            wrong |= any(healthy[o] != faulty[o] for o in c.outputs)
            obs += [Literal(f"{i}@{j}", faulty[i]) for i in c.inputs]
            obs += [Literal(f"{o}@{j}", faulty[o]) for o in dict.fromkeys(c.outputs)]
        if wrong:
            out.append(obs)
    return out


# -- the tables ----------------------------------------------------------------------------------
def _cell(xs: list[float]) -> str:
    done = [x for x in xs if x != float("inf")]
    if not done:
        return "cut"
    cut = len(xs) - len(done)
    return (f"{_ms(statistics.fmean(done))} / {_ms(max(done))}"
            + (f" ({cut} cut)" if cut else ""))


def _ms(s: float) -> str:
    return f"{s * 1000:.1f} ms" if s < 1 else f"{s:.2f} s"


COMPILED: list[float] = []  # each model's compile time (encoding and structure), CPU


def _compare(theory: Theory, instances: list[list[Literal]], budget: float
             ) -> tuple[dict[str, list[float]], list[int]]:
    times: dict[str, list[float]] = {"dxboard": [], "RC2": [], "LSU": []}
    cards: list[int] = []
    known = theory.observable_atoms()
    # compiled as the product compiles a model (``cache.py``: the encoding with its circuit
    # structure, kept beside the parsed model), before the clock: a one-time cost per model
    # like the peers' formula building; reported beside the table (``COMPILED``)
    t = CPU()
    encoding = encode(theory, structure=True)
    COMPILED.append(CPU() - t)
    with Diagnoser(theory, encoding=encoding) as d:
        for obs in instances:
            obs = [o for o in obs if o.atom in known]
            d.assume(obs)
            t, k = cpu_run(ours_first, d, budget)
            times["dxboard"].append(t if k is not None else float("inf"))
            for name, run in (("RC2", rc2_first), ("LSU", lsu_first)):
                wcnf, _ = _wcnf(theory, obs)  # the formula as a peer is given it: not timed
                tp, kp = cpu_run(run, wcnf, budget)
                times[name].append(tp if kp is not None else float("inf"))
                if k is not None and kp is not None:
                    assert k == kp, (name, k, kp)  # every peer finds the same minimum
            if k is not None:
                cards.append(k)
    return times, cards


def _row(label: str, gates: int, n: int, times: dict[str, list[float]], cards: list[int]
         ) -> str:
    done = {p: [x for x in xs if x != float("inf")] for p, xs in times.items()}
    ours = statistics.fmean(done["dxboard"]) if done["dxboard"] else float("inf")
    peers = [statistics.fmean(done[p]) for p in ("RC2", "LSU")
             if done[p] and len(done[p]) == len(times[p])]
    ratio = f"{min(peers) / ours:.2f}x" if peers and ours != float("inf") else "-"
    over = sum(x > 1.0 for x in times["dxboard"])
    card = f"{min(cards)}-{max(cards)}" if cards else "-"
    return (f"| {label} | {gates} | {n} | {card} | {_cell(times['dxboard'])} | {over} | "
            f"{_cell(times['RC2'])} | {_cell(times['LSU'])} | {ratio} |")


HEADER = ("| instances | gates | n | min card | dxboard mean / worst | dxboard > 1 s | "
          "RC2 mean / worst | LSU mean / worst | fastest complete peer / dxboard |\n"
          "|---|---|---|---|---|---|---|---|---|")


def bench_first(args: argparse.Namespace, lines: list[str]) -> None:
    rng = random.Random(args.seed)
    lines.append(f"First minimum-cardinality diagnosis, CPU time per instance (seed {args.seed},"
                 f" budget {args.budget:g} s wall each; load average "
                 f"{os.getloadavg()[0]:.1f} at the start):\n")
    lines.append(HEADER)
    compiled: list[str] = []
    for name in CIRCUITS:
        circuit = parse_bench(ISCAS / f"{name}.bench")
        instances = [obs for _f, obs in sample(circuit, rng, args.per_circuit)]
        if name not in args.circuits:
            continue
        times, cards = _compare(circuit_theory(circuit), instances, args.budget)
        lines.append(_row(name, len(circuit.gates), len(instances), times, cards))
        print(lines[-1], flush=True)
        compiled.append(f"{name} {_ms(COMPILED[-1])}")
    lines.append(f"\n(compiled once per model before the clock, as the model cache keeps it: "
                 f"{', '.join(compiled)})")
    lines.append(f"(load average {os.getloadavg()[0]:.1f} at the end)\n")


def bench_multi(args: argparse.Namespace, lines: list[str]) -> None:
    rng = random.Random(args.seed)
    lines.append("Multiple observations (generated: one faulty circuit, m input vectors; a "
                 "diagnosis consistent with all), first minimum cardinality, CPU time per "
                 f"instance (load average {os.getloadavg()[0]:.1f} at the start):\n")
    lines.append(HEADER)
    for name in args.multi_circuits:
        circuit = parse_bench(ISCAS / f"{name}.bench")
        for m in args.observations:
            theory = multi_theory(circuit, m)
            instances = multi_sample(circuit, rng, args.per_circuit, m)
            times, cards = _compare(theory, instances, args.budget)
            lines.append(_row(f"{name} x {m} obs", len(circuit.gates), len(instances), times,
                              cards))
            print(lines[-1], flush=True)
    lines.append(f"(load average {os.getloadavg()[0]:.1f} at the end)\n")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--circuits", nargs="+", choices=CIRCUITS,
                        default=["c432", "c499", "c880", "c1355", "c2670", "c6288"])
    parser.add_argument("--multi-circuits", nargs="+", choices=CIRCUITS,
                        default=["c432", "c880", "c1908"])
    parser.add_argument("--observations", default="2,4,8",
                        type=lambda s: [int(x) for x in s.split(",")])
    parser.add_argument("--per-circuit", type=int, default=10)
    parser.add_argument("--budget", type=float, default=30.0, help="each run's wall budget, s")
    parser.add_argument("--seed", type=int, default=20261128)
    parser.add_argument("--only", choices=["first", "multi"], default=None)
    args = parser.parse_args()
    lines: list[str] = []
    if args.only in (None, "first"):
        bench_first(args, lines)
    if args.only in (None, "multi"):
        bench_multi(args, lines)
    print("\n".join(lines))


if __name__ == "__main__":
    main()
