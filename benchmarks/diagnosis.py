"""Diagnosis benchmark: ISCAS-85 circuits, the whole command, and synthetic robot models.

ISCAS-85 (benchmarks/iscas.py; ``shared/data/iscas85`` beside the checkout or a folder above
it, or ``$DXBOARD_SHARED/data/iscas85``): a *fresh* sample the benchmark draws itself, seeded
(``--seed``, printed), ``--per-circuit`` instances per circuit (30 by default), each with 1-5
random gates flipped and every primary input and output observed. Per instance, with the
diagnoser built once per circuit: the first minimal-cardinality diagnosis (``max_count`` 1) by
the default algorithm ``auto`` and by ``cardinality``; all minimal-cardinality diagnoses (up
to 1,000) by ``auto``; and, beside them in the same run, the reference: PySAT's RC2 on the
whole model, first optimum. Instances of minimum cardinality above 5 are counted apart. The
table reports the mean and the *worst* instance, and how many missed 1 s / 5 s.

All subset-minimal diagnoses up to cardinality 1, 2, 3 on ``--all-circuits`` (c432, c499,
c880), against live peers run here on the same instances: a plain HS-tree and an HS-DAG over
the same SAT solver, RC2 enumeration and LBX (PySAT); PyMBD's c432 figures stand beside as
published, not run.

The whole command (benchmarks/command_bench.py): ``dxboard diagnose MODEL.yaml --obs FILE
--json --min-card-only`` as a process, on circuits written as tug model files, against the
engine alone on the same instance (in process, the model loaded; also given the encoding the
command caches, and timed around its calls in a fresh process), in wall and in CPU time;
``--base DIR`` runs the command from another checkout too (the code before a change:
``git archive REV | tar -x -C DIR``), interleaved, and times the start-up (``dxboard diagnose
--help``) of both.

Synthetic robots: layered robot models of 100, 1,000 and 10,000 components in system.yaml
form; with every observer reporting, one observation at a time flips and flips back; each
re-diagnosis (observe -> diagnose) is timed, p50/p99.

    .venv/bin/python benchmarks/diagnosis.py [--quick] [--seed N] [--per-circuit N]
        [--only iscas|peers|command|rc2|robots] [--all-circuits A,B] [--base DIR] [--write]

``--write`` replaces the "## Diagnosis" section of benchmarks/RESULTS.md.
"""

from __future__ import annotations

import argparse
import functools
import os
import platform
import random
import statistics
import sys
import tempfile
import time
from collections import deque
from pathlib import Path
from typing import Any

import yaml

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from benchmarks.command_bench import (  # noqa: E402
    MAX_COUNT,
    bench_command,
    bench_rc2_process,
    cpu_timed,
    fmt,
    mean_worst,
    timed,
)
from benchmarks.iscas import (  # noqa: E402
    CIRCUITS,
    ISCAS,
    circuit_theory,
    lbx_all,
    parse_bench,
    rc2_all,
    rc2_reference,
    sample,
)
from host.diagnosis import (  # noqa: E402
    Diagnoser,
    DiagnosisResult,
    Literal,
    Theory,
    generate,
    load_system,
)
from host.diagnosis.encoding import encode  # noqa: E402
from host.diagnosis.satctx import SatContext  # noqa: E402
from host.diagnosis.structure import infer_structure  # noqa: E402

PYMBD_C432 = {1: 0.68, 2: 2.7, 3: 10.2}  # s, PyMBD's best algorithm, all min. diagnoses <= k
MAX_CARD = 5


# -- the baseline: a plain Reiter HS-tree ----------------------------------------------------
def hs_tree(ctx: SatContext, obs: list[int], max_card: int, min_card_only: bool,
            budget_s: float, dag: bool = True) -> tuple[list[frozenset[int]], bool]:
    """Breadth-first HS-tree (Reiter: conflicts reused as labels, nodes holding a diagnosis
    closed); ``dag``: HS-DAG, a node reached again by another path is not expanded twice.
    Returns (minimal diagnoses, complete)."""
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
        if (dag and h in seen) or any(d <= h for d in diagnoses):
            continue
        if dag:
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
def thread_timed(fn, *args, **kw):  # type: ignore[no-untyped-def]
    """This thread's CPU time and the result (the budgets' timers run in threads of their
    own; every search here is single-threaded)."""
    c = time.thread_time()
    r = fn(*args, **kw)
    return time.thread_time() - c, r


def worst(xs: list[float]) -> str:
    return mean_worst(xs).split(" / ")[-1]


def first_card(r: DiagnosisResult) -> int | None:
    return r.diagnoses[0].cardinality if r.diagnoses else None


def bench_iscas(args: argparse.Namespace, lines: list[str]) -> None:
    rng = random.Random(args.seed)
    names = CIRCUITS[:5] if args.quick else args.circuits or CIRCUITS
    lines.append("### ISCAS-85, weak fault model: a fresh sample, worst case beside RC2\n")
    lines.append(f"Seed {args.seed}, {args.per_circuit} instances per circuit (1-5 gates flipped, "
                 "every input and output observed), drawn by the benchmark itself. Times per "
                 "instance; the diagnoser is built once per circuit. *first*: the first "
                 "minimal-cardinality diagnosis (`--min-card-only --max-count 1`); *all*: "
                 f"every minimal-cardinality diagnosis up to {MAX_COUNT}; RC2: PySAT's RC2 on "
                 "the whole model, first optimum, same run. Budgets: ours "
                 f"{args.budget:g} s, `cardinality` {args.card_budget:g} s, RC2 "
                 f"{args.ref_budget:g} s. Instances of minimum cardinality above {MAX_CARD} "
                 "are listed apart (`>5`); *cut*: a budget stopped one (left out of the "
                 "mean). *CPU*: this process's CPU time for the same request (the search is "
                 "single-threaded: near what an unloaded machine takes; the budgets count "
                 "wall time).\n")
    lines.append("| circuit | gates | top-level | instances (>5) | min card | first, `auto` "
                 "mean / worst | > 1 s | first, CPU worst | first, `cardinality` mean / worst | "
                 "RC2 mean / worst | all (<= 1000), `auto` mean / worst | > 5 s | all, CPU "
                 "worst | #diagnoses max | cut by count |")
    lines.append("|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|")
    for name in CIRCUITS:
        circuit = parse_bench(ISCAS / f"{name}.bench")
        instances = sample(circuit, rng, args.per_circuit)  # drawn for all: same sample
        if name not in names:
            continue
        theory = circuit_theory(circuit)
        known = theory.observable_atoms()  # an output wired to an input may be in no clause
        structure = infer_structure(theory)
        top = len(structure.regions(set(circuit.inputs) | set(circuit.outputs))) \
            if structure is not None else len(theory.components)
        d = Diagnoser(theory)
        dcard = Diagnoser(theory, algorithm="cardinality")
        first, card, ref, alls, cards, counts = [], [], [], [], [], []
        first_cpu: list[float] = []
        all_cpu: list[float] = []
        over5 = cut_count = 0
        for _flips, obs in instances:
            obs = [o for o in obs if o.atom in known]
            for o in obs:
                d.observe(o)
                dcard.observe(o)
            t_ref, k_ref = rc2_reference(theory, obs, args.ref_budget)
            t, cpu, r = cpu_timed(d.diagnose, min_card_only=True, max_count=1,
                                  time_budget_s=args.budget)
            k = first_card(r)
            if k is not None and k_ref is not None:
                assert k == k_ref, (name, k, k_ref)  # the reference agrees on the minimum
            if (k if k is not None else k_ref or 0) > MAX_CARD:
                over5 += 1
                continue
            first.append(t if k is not None else float("inf"))
            first_cpu.append(cpu if k is not None else float("inf"))
            ref.append(t_ref)
            cards.append(k or -1)
            t, r = timed(dcard.diagnose, min_card_only=True, max_count=1,
                         time_budget_s=args.card_budget)
            card.append(t)
            t, cpu, r = cpu_timed(d.diagnose, min_card_only=True, max_count=MAX_COUNT,
                                  time_budget_s=args.budget)
            done = r.cut_by is None or r.cut_by.value == "max_count"
            alls.append(t if done else float("inf"))
            all_cpu.append(cpu if done else float("inf"))
            counts.append(len(r.diagnoses))
            cut_count += r.cut_by is not None and r.cut_by.value == "max_count"
        d.close()
        dcard.close()
        ks = [c for c in cards if c >= 0]
        lines.append(
            f"| {name} | {len(circuit.gates)} | {top} | {len(first)} ({over5}) | "
            f"{min(ks) if ks else '-'}-{max(ks) if ks else '-'} | {mean_worst(first)} | "
            f"{sum(t > 1 for t in first)} | {worst(first_cpu)} | {mean_worst(card)} | "
            f"{mean_worst(ref)} | {mean_worst(alls)} | {sum(t > 5 for t in alls)} | "
            f"{worst(all_cpu)} | {max(counts, default=0)} | {cut_count} |")
        print(lines[-1], flush=True)
    lines.append("")


PEERS = ("HS-tree", "HS-DAG", "RC2 enum", "LBX")


def bench_c432(args: argparse.Namespace, lines: list[str]) -> None:
    """All subset-minimal diagnoses up to k on the ISCAS-85 circuits ``--all-circuits``, dxboard
    against live peers in this run: a plain HS-tree and an HS-DAG over the same SAT solver,
    RC2 enumeration and LBX (PySAT). Each peer's answer, when complete, must equal ours.
    Each HS peer gets a fresh solver of its own for each run (none runs on a solver another
    warmed with the same queries); the engines run in an order rotated per instance and k
    (none always follows LBX's long cut run); times are this thread's CPU time."""
    rng = random.Random(args.seed)
    lines.append("All subset-minimal diagnoses up to cardinality k (mean CPU time per "
                 f"instance, same seed; load average {os.getloadavg()[0]:.1f} at the start). "
                 "Live peers run here in the same process, each HS peer on a fresh solver of "
                 "its own; PyMBD's c432 figures are published, not run:\n")
    lines.append("| circuit | k | dxboard | " + " | ".join(PEERS)
                 + " | fastest peer / dxboard | PyMBD best (published, not run) |")
    lines.append("|---|---|---|" + "---|" * len(PEERS) + "---|---|")
    for name in args.all_circuits.split(","):
        circuit = parse_bench(ISCAS / f"{name}.bench")
        theory = circuit_theory(circuit)
        known = theory.observable_atoms()
        enc = encode(theory)
        ours: dict[int, list[float]] = {1: [], 2: [], 3: []}
        peers: dict[tuple[str, int], list[float]] = {(p, k): [] for p in PEERS for k in (1, 2, 3)}
        cut: set[tuple[str, int]] = set()
        with Diagnoser(theory) as d:
            for i, (_flips, obs) in enumerate(sample(circuit, rng, 5 if args.quick else 10)):
                obs = [o for o in obs if o.atom in known]
                for o in obs:
                    d.observe(o)
                for k in (1, 2, 3):
                    tree, dag = SatContext(theory, encoding=enc), SatContext(theory, encoding=enc)
                    runs: list[tuple[str, Any, tuple[Any, ...]]] = [
                        ("dxboard", functools.partial(d.diagnose, max_card=k, max_count=100000,
                                                      time_budget_s=args.budget), ()),
                        ("HS-tree", hs_tree, (tree, [tree.lit(o) for o in obs], k, False,
                                              args.base_budget, False)),
                        ("HS-DAG", hs_tree, (dag, [dag.lit(o) for o in obs], k, False,
                                             args.base_budget)),
                        ("RC2 enum", rc2_all, (theory, obs, k, args.base_budget)),
                        ("LBX", lbx_all, (theory, obs, k, args.lbx_budget)),
                    ]
                    # an order rotated per instance and k: no engine always runs right after
                    # LBX's cut 0.8 s, which leaves the CPU's caches cold (about 2x on a
                    # request of a millisecond)
                    shift = (i + k) % len(runs)
                    timed = {who: thread_timed(run, *run_args)
                             for who, run, run_args in runs[shift:] + runs[:shift]}
                    t, r = timed["dxboard"]
                    ours[k].append(t)
                    got = {frozenset(theory.components.index(x) for x in b)
                           for b in r.bad_sets()}
                    for peer in PEERS:
                        t, (diags, complete) = timed[peer]
                        peers[peer, k].append(t)
                        if complete:  # cross-check
                            assert set(diags) == got, (name, k, peer)
                        else:
                            cut.add((peer, k))
                    tree.close()
                    dag.close()
        for k in (1, 2, 3):
            o = statistics.fmean(ours[k])
            cells = [fmt(statistics.fmean(peers[p, k])) + (" (cut)" if (p, k) in cut else "")
                     for p in PEERS]
            done = [statistics.fmean(peers[p, k]) for p in PEERS if (p, k) not in cut]
            ratio = f"{min(done) / o:.2f}x" if done else "every peer cut"
            pymbd = f"{PYMBD_C432[k]:.2f} s" if name == "c432" else "-"
            lines.append(f"| {name} | {k} | {fmt(o)} | " + " | ".join(cells)
                         + f" | {ratio} | {pymbd} |")
            print(lines[-1], flush=True)
    lines.append("")


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
    parser.add_argument("--quick", action="store_true", help="a small run (a few minutes)")
    parser.add_argument("--write", action="store_true", help="update benchmarks/RESULTS.md")
    parser.add_argument("--seed", type=int, default=int(time.strftime("%Y%m%d")),
                        help="the sample's seed (default: today's date)")
    parser.add_argument("--per-circuit", type=int, default=30, help="instances per circuit")
    parser.add_argument("--budget", type=float, default=5.0, help="our time budget, s")
    parser.add_argument("--card-budget", type=float, default=5.0,
                        help="the `cardinality` column's budget, s")
    parser.add_argument("--ref-budget", type=float, default=30.0, help="RC2's budget, s")
    parser.add_argument("--base-budget", type=float, default=5.0,
                        help="each live peer's budget per instance, s")
    parser.add_argument("--lbx-budget", type=float, default=1.0,
                        help="LBX's budget per instance, s (it lists every minimal diagnosis, "
                        "in no order of size: cut everywhere at 5 s too)")
    parser.add_argument("--all-circuits", default="c432,c499,c880", metavar="A,B",
                        help="ISCAS-85 circuits of the all-diagnoses comparison with live "
                             "peers (default: c432,c499,c880)")
    parser.add_argument("--base", type=Path, default=None, metavar="DIR",
                        help="the whole command: also run it from this checkout (the code "
                        "before a change, e.g. `git archive REV | tar -x -C DIR`), interleaved")
    parser.add_argument("--repeat", type=int, default=2, metavar="N",
                        help="the whole command: runs of each kind per instance, the best "
                        "counted (default: 2)")
    parser.add_argument("--only", choices=["iscas", "peers", "command", "rc2", "robots"],
                        default=None,
                        help="one part (peers: the all-diagnoses comparison alone; rc2: the "
                        "command against RC2 as a process)")
    parser.add_argument("--circuits", nargs="+", choices=CIRCUITS, metavar="NAME",
                        help="measure these circuits only (the sample is drawn as for all; "
                        "the whole command too)")
    args = parser.parse_args()
    if args.quick:
        args.per_circuit = min(args.per_circuit, 10)
    load = os.getloadavg()[0] if hasattr(os, "getloadavg") else float("nan")
    lines = ["## Diagnosis", "",
             f"`benchmarks/diagnosis.py{' --quick' if args.quick else ''}`, "
             f"{time.strftime('%Y-%m-%d')}, {os.cpu_count()} cores (load average "
             f"{load:.1f} at the start: the machine is shared), Python "
             f"{platform.python_version()}, PySAT Glucose 4 via python-sat (RC2 over Glucose "
             "3 for `maxsat`/`top-level`), default algorithm `auto`.", ""]
    if args.only in (None, "iscas"):
        bench_iscas(args, lines)
    if args.only in (None, "iscas", "peers"):
        bench_c432(args, lines)
    if args.only in (None, "command"):
        bench_command(args, lines)
    if args.only in (None, "command", "rc2"):
        bench_rc2_process(args, lines)
    if args.only in (None, "robots"):
        bench_robots(args, lines)
    section = "\n".join(lines)
    print(section)
    if args.write:
        write_results(section)


if __name__ == "__main__":
    main()
