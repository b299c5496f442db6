"""Diagnosis benchmark: ISCAS-85 circuits and synthetic robot models, in one run.

ISCAS-85 (``../shared/data/iscas85`` beside the checkout): each gate is a component under the
weak fault model (``AB(g) or out(g) = f(inputs)``). Observations come from simulating the
circuit on random inputs with 1-5 gate outputs flipped (kept only when an output differs),
and observe every primary input and output. Measured per instance, with the solver built
once per circuit (its build time is reported apart): the time to all minimal-cardinality
diagnoses (cardinality <= 5), and to all subset-minimal diagnoses up to cardinality 1, 2, 3.
The baseline, on the same instances and the same SAT oracle, is a plain Reiter HS-tree
(breadth-first, conflicts from unsatisfiable cores, reused when they stay unhit, subset
pruning); it has a time budget per instance, so a speedup over a cut baseline is a lower bound.

Synthetic robots: layered robot models of 100, 1,000 and 10,000 components in system.yaml
form, loaded and generated as usual; with every observer reporting, one observation at a time
flips (a device loses power, a node stops, a topic goes silent) and flips back; we time each
re-diagnosis (observe -> diagnose) and report p50/p99.

    .venv/bin/python benchmarks/diagnosis.py [--quick] [--write]

``--write`` replaces the "## Diagnosis" section of benchmarks/RESULTS.md.
"""

from __future__ import annotations

import argparse
import platform
import random
import statistics
import sys
import tempfile
import time
from collections import deque
from dataclasses import dataclass
from pathlib import Path

import yaml

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from host.diagnosis import (  # noqa: E402
    Clause,
    Diagnoser,
    DiagnosisResult,
    Literal,
    Theory,
    ab,
    generate,
    load_system,
)
from host.diagnosis.satctx import SatContext  # noqa: E402

ISCAS = ROOT / ".." / "shared" / "data" / "iscas85"
CIRCUITS = ["c17", "c432", "c499", "c880", "c1355", "c1908", "c2670", "c3540", "c5315",
            "c6288", "c7552"]
PYMBD_C432 = {1: 0.68, 2: 2.7, 3: 10.2}  # s, PyMBD's best algorithm, all min. diagnoses <= k


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


def instances(c: Circuit, rng: random.Random, per_fault_count: int) -> list[list[Literal]]:
    gates = [g[0] for g in c.gates]
    out: list[list[Literal]] = []
    for n_faults in range(1, 6):
        made = 0
        while made < per_fault_count:
            inputs = {i: rng.random() < 0.5 for i in c.inputs}
            flips = set(rng.sample(gates, min(n_faults, len(gates))))
            healthy = simulate(c, inputs, set())
            faulty = simulate(c, inputs, flips)
            if all(healthy[o] == faulty[o] for o in c.outputs):
                continue
            obs = [Literal(i, faulty[i]) for i in c.inputs]
            obs += [Literal(o, faulty[o]) for o in dict.fromkeys(c.outputs)]
            out.append(obs)
            made += 1
    return out


# -- the baseline: a plain Reiter HS-tree ----------------------------------------------------
def hs_tree(ctx: SatContext, obs: list[int], max_card: int, min_card_only: bool,
            budget_s: float) -> tuple[list[frozenset[int]], bool]:
    """Breadth-first HS-tree; returns (minimal diagnoses, complete)."""
    deadline = time.perf_counter() + budget_s
    n = len(ctx.ab_vars)
    conflicts: list[frozenset[int]] = []
    diagnoses: list[frozenset[int]] = []
    seen: set[frozenset[int]] = set()
    queue: deque[frozenset[int]] = deque([frozenset()])
    while queue:
        if time.perf_counter() > deadline:
            return diagnoses, False
        h = queue.popleft()
        if len(h) > max_card:
            return diagnoses, True
        if min_card_only and diagnoses and len(h) > len(diagnoses[0]):
            return diagnoses, True
        if h in seen or any(d <= h for d in diagnoses):
            continue
        seen.add(h)
        label = next((c for c in conflicts if not (c & h)), None)
        if label is None:
            if ctx.solve(obs + [-ctx.ab_vars[i] for i in range(n) if i not in h]):
                diagnoses.append(h)
                continue
            label = frozenset(ctx.index_of_ab[-lit] for lit in ctx.core()
                              if -lit in ctx.index_of_ab)
            conflicts.append(label)
        for comp in label:
            queue.append(h | {comp})
    return diagnoses, True


# -- running ------------------------------------------------------------------------------------
def timed(fn, *args, **kw):  # type: ignore[no-untyped-def]
    t = time.perf_counter()
    r = fn(*args, **kw)
    return time.perf_counter() - t, r


def fmt(s: float) -> str:
    return f"{s * 1000:.1f} ms" if s < 1 else f"{s:.2f} s"


def card_range(cards: list[int]) -> str:
    """``lo-hi`` of the min cards found; ``-1`` marks instances the budget cut first."""
    found = [c for c in cards if c >= 0]
    cut = len(cards) - len(found)
    text = f"{min(found)}-{max(found)}" if found else "none"
    return text + (f" ({cut} cut)" if cut else "")


def bench_iscas(args: argparse.Namespace, lines: list[str]) -> None:
    rng = random.Random(2026)
    per = 1 if args.quick else 2
    names = CIRCUITS[:4] if args.quick else CIRCUITS
    base_names = {"c17", "c432", "c499", "c880"} if not args.quick else {"c17", "c432"}
    lines.append("### ISCAS-85, weak fault model\n")
    lines.append(f"{per} observation(s) per number of flipped gates (1-5), so {5 * per} "
                 "instances per circuit; times per instance, solver built once per circuit. "
                 "*min-card*: all minimal-cardinality diagnoses (cardinality <= 5, count <= "
                 "1000; *first*: max count 1); *all <= 3*: all subset-minimal diagnoses up "
                 "to cardinality 3 "
                 f"(time budget {args.budget:g} s each). Baseline: plain Reiter HS-tree, "
                 f"same SAT oracle, budget {args.base_budget:g} s per instance and task.\n")
    lines.append("| circuit | gates | build | first min-card diag. mean / max | same, "
                 "`cardinality` mean / max | same, `maxsat` "
                 "mean / max | all min-card mean / max | min card | #min-card (max) | "
                 "all <= 3 mean / max | #diag <= 3 (max) | cut by budget/count | HS-tree "
                 "min-card mean | HS-tree all <= 3 mean | speedup vs HS-tree min-card / all <= 3 |")
    lines.append("|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|")
    c432_levels: dict[int, list[float]] = {1: [], 2: [], 3: []}
    c432_base: dict[int, list[float]] = {1: [], 2: [], 3: []}
    for name in names:
        circuit = parse_bench(ISCAS / f"{name}.bench")
        theory = circuit_theory(circuit)
        build, d = timed(Diagnoser, theory)
        known = theory.observable_atoms()  # an output wired to an input may be in no clause
        insts = [[o for o in obs if o.atom in known] for obs in instances(circuit, rng, per)]
        mc_t, mc_card, mc_n, a3_t, a3_n, cuts = [], [], [], [], [], 0
        first_t, first_mx, first_card = [], [], []
        dmx = Diagnoser(theory, algorithm="maxsat")
        dcard = Diagnoser(theory, algorithm="cardinality")
        b_mc, b_a3 = [], []
        base_cut = 0
        for obs in insts:
            for o in obs:
                d.observe(o)
                dmx.observe(o)
                dcard.observe(o)
            t, r = timed(d.diagnose, max_card=5, max_count=1, time_budget_s=args.budget,
                         min_card_only=True)
            first_t.append(t)
            cuts += r.cut_by is not None and r.cut_by.value == "time_budget"
            t, r = timed(dcard.diagnose, max_card=5, max_count=1, time_budget_s=args.budget,
                         min_card_only=True)
            first_card.append(t)
            t, r = timed(dmx.diagnose, max_card=5, max_count=1, time_budget_s=args.budget,
                         min_card_only=True)
            first_mx.append(t)
            t, r = timed(d.diagnose, max_card=5, max_count=1000, time_budget_s=args.budget,
                         min_card_only=True)
            mc_t.append(t)
            mc_card.append(r.diagnoses[0].cardinality if r.diagnoses else -1)
            mc_n.append(len(r.diagnoses))
            cuts += not r.complete
            t, r = timed(d.diagnose, max_card=3, max_count=100000, time_budget_s=args.budget)
            a3_t.append(t)
            a3_n.append(len(r.diagnoses))
            cuts += not r.complete and r.cut_by is not None and r.cut_by.value != "max_card"
            if name == "c432":
                for k in (1, 2, 3):
                    t, r = timed(d.diagnose, max_card=k, max_count=100000,
                                 time_budget_s=args.budget)
                    c432_levels[k].append(t)
            if name in base_names:
                ctx = SatContext(theory)
                lits = [ctx.lit(o) for o in obs]
                t, (diags, complete) = timed(hs_tree, ctx, lits, 5, True, args.base_budget)
                b_mc.append(t)
                base_cut += not complete
                if complete:  # cross-check
                    ours = {frozenset(theory.components.index(x) for x in b)
                            for b in d.diagnose(max_card=5, max_count=1000,
                                                time_budget_s=args.budget,
                                                min_card_only=True).bad_sets()}
                    assert set(diags) == ours or len(ours) >= 1000, name
                t, (diags, complete) = timed(hs_tree, ctx, lits, 3, False, args.base_budget)
                b_a3.append(t)
                base_cut += not complete
                if name == "c432":
                    for k in (1, 2, 3):
                        t, _ = timed(hs_tree, ctx, lits, k, False, args.base_budget)
                        c432_base[k].append(t)
                ctx.close()
        d.close()
        dmx.close()
        dcard.close()
        mean = statistics.fmean
        if b_mc:
            base_cols = (f"{fmt(mean(b_mc))} | {fmt(mean(b_a3))} | "
                         f"{'>=' if base_cut else ''}{sum(b_mc) / sum(mc_t):.1f}x / "
                         f"{'>=' if base_cut else ''}{sum(b_a3) / sum(a3_t):.1f}x")
        else:
            base_cols = "- | - | -"
        lines.append(
            f"| {name} | {len(circuit.gates)} | {fmt(build)} | {fmt(mean(first_t))} / "
            f"{fmt(max(first_t))} | {fmt(mean(first_card))} / {fmt(max(first_card))} | "
            f"{fmt(mean(first_mx))} / {fmt(max(first_mx))} | "
            f"{fmt(mean(mc_t))} / "
            f"{fmt(max(mc_t))} | {min(mc_card)}-{max(mc_card)} | {max(mc_n)} | "
            f"{fmt(mean(a3_t))} / {fmt(max(a3_t))} | {max(a3_n)} | {cuts} | {base_cols} |")
        print(lines[-1], flush=True)
    lines.append("")
    lines.append("c432, all subset-minimal diagnoses up to cardinality k (mean per instance):\n")
    lines.append("| k | PyMBD best (published) | dxboard | speedup vs PyMBD | HS-tree (here) | "
                 "speedup vs HS-tree |")
    lines.append("|---|---|---|---|---|---|")
    for k in (1, 2, 3):
        ours = statistics.fmean(c432_levels[k])
        base = statistics.fmean(c432_base[k]) if c432_base[k] else float("nan")
        lines.append(f"| {k} | {PYMBD_C432[k]:.2f} s | {fmt(ours)} | "
                     f"{PYMBD_C432[k] / ours:.0f}x | {fmt(base)} | {base / ours:.0f}x |")
        print(lines[-1], flush=True)
    lines.append("")


# -- synthetic robots ----------------------------------------------------------------------------
def robot_yaml(n: int, rng: random.Random) -> dict[str, object]:
    comps: dict[str, dict[str, object]] = {}
    n_sh = max(1, n // 10)
    n_h = max(1, n // 20)
    topics: list[str] = []
    for i in range(n_sh):
        comps[f"dev{i}"] = {"kind": "SH", "channel": i, "current": [0.1, 2.0]}
        comps[f"drv{i}"] = {"kind": "SN", "hardware": [f"dev{i}"],
                            "publishes": {f"/raw{i}": []}}
        topics.append(f"/raw{i}")
    for i in range(n_h):
        comps[f"hw{i}"] = {"kind": "H"}
        comps[f"hwn{i}"] = {"kind": "HN", "hardware": [f"hw{i}"], "publishes": [f"/hw{i}"]}
        topics.append(f"/hw{i}")
    i = 0
    while len(comps) < n:
        ins = sorted(set(rng.sample(topics[-50:], min(len(topics), rng.randint(1, 3)))))
        comps[f"node{i}"] = {"kind": "N", "subscribes": ins, "publishes": {f"/t{i}": ins}}
        topics.append(f"/t{i}")
        i += 1
    return {"robot": f"synthetic{n}", "board": {"channels": n_sh}, "components": comps}


def healthy_observations(theory: Theory) -> list[Literal]:
    obs = []
    for atom in sorted(theory.observable_atoms()):
        if atom.split("(")[0] in ("on", "running", "ok", "in_band"):
            obs.append(Literal(atom, True))
        elif atom.startswith("tripped("):
            obs.append(Literal(atom, False))
    return obs


def change(d: Diagnoser, lit: Literal) -> DiagnosisResult:
    """One changed observation -> the new diagnoses (what the latency measures)."""
    d.observe(lit)
    return d.diagnose()


def pct(sorted_samples: list[float], q: float) -> float:
    return sorted_samples[min(len(sorted_samples) - 1, int(q * len(sorted_samples)))]


def bench_robots(args: argparse.Namespace, lines: list[str]) -> None:
    rng = random.Random(7)
    sizes = [100, 1000] if args.quick else [100, 1000, 10000]
    lines.append("### Synthetic robot models: one changed observation -> new diagnoses\n")
    lines.append("Layered models (10% switchable devices with their drivers, 5% other hardware "
                 "with hardware nodes, the rest ordinary nodes reading 1-3 recent topics), "
                 "every observer reporting. Each sample flips one random observation (a "
                 "device off, a node stopped, a topic silent) and then flips it back; the time "
                 "is observe + diagnose (all minimal diagnoses, no bound), solver kept.\n")
    lines.append("| components | clauses | observations | load+generate | build | samples | "
                 "p50 | p99 | max |")
    lines.append("|---|---|---|---|---|---|---|---|---|")
    for n in sizes:
        with tempfile.TemporaryDirectory() as tmp:
            (Path(tmp) / "system.yaml").write_text(yaml.safe_dump(robot_yaml(n, rng)))
            t_load, theory = timed(lambda: generate(load_system(tmp)))
        t_build, d = timed(Diagnoser, theory)
        obs = healthy_observations(theory)
        for o in obs:
            d.observe(o)
        first = d.diagnose()
        assert first.bad_sets() == [frozenset()]
        samples = []
        candidates = [o for o in obs if o.positive]
        count = 100 if n >= 10000 else 300
        for _ in range(count):
            o = rng.choice(candidates)
            t, r = timed(change, d, -o)
            assert r.complete and r.diagnoses and r.diagnoses[0].bad, o
            samples.append(t)
            t, r = timed(change, d, o)
            assert r.bad_sets() == [frozenset()]
            samples.append(t)
        samples.sort()
        lines.append(f"| {n:,} | {len(theory.clauses):,} | {len(obs):,} | {fmt(t_load)} | "
                     f"{fmt(t_build)} | {len(samples)} | {fmt(pct(samples, 0.5))} | "
                     f"{fmt(pct(samples, 0.99))} | "
                     f"{fmt(samples[-1])} |")
        print(lines[-1], flush=True)
        d.close()
    lines.append("")


def write_results(section: str) -> None:
    path = ROOT / "benchmarks" / "RESULTS.md"
    if path.exists():
        text = path.read_text()
    else:
        text = ("# Benchmark results\n\nMeasured on a machine with 2 cores, Python "
                f"{platform.python_version()}, {time.strftime('%Y-%m-%d')}.\n")
    start = text.find("\n## Diagnosis")
    if start >= 0:
        end = text.find("\n## ", start + 1)
        text = text[:start] + text[end if end >= 0 else len(text):]
    path.write_text(text.rstrip("\n") + "\n\n" + section.rstrip("\n") + "\n")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--quick", action="store_true", help="a small run (a minute)")
    parser.add_argument("--write", action="store_true", help="update benchmarks/RESULTS.md")
    parser.add_argument("--budget", type=float, default=5.0, help="our time budget, s")
    parser.add_argument("--base-budget", type=float, default=5.0, help="HS-tree budget, s")
    parser.add_argument("--only", choices=["iscas", "robots"], default=None)
    args = parser.parse_args()
    lines = ["## Diagnosis", "",
             f"`benchmarks/diagnosis.py{' --quick' if args.quick else ''}`, "
             f"{time.strftime('%Y-%m-%d')}, 2 cores, Python {platform.python_version()}, "
             "PySAT Glucose 4 via python-sat (RC2 over Glucose 3 for `maxsat`/`top-level`), "
             "default algorithm `auto`.", ""]
    if args.only in (None, "iscas"):
        bench_iscas(args, lines)
    if args.only in (None, "robots"):
        bench_robots(args, lines)
    section = "\n".join(lines)
    print(section)
    if args.write:
        write_results(section)


if __name__ == "__main__":
    main()
