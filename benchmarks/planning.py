"""Repair planning: our A* against Fast Downward on the same PDDL files, in one run.

Synthetic robots of N components (a quarter switchable devices, each with its driver node;
the rest ordinary nodes that need one or two earlier drivers or nodes, so dependencies form
a shallow DAG) with the tedusar domain (models/tedusar/repair.pddl). Cases:

* power-up of N components (paper 000 §VI-A): everything off and abnormal;
* single-fault repair (§VI-B) among N: one device off under its running driver
  (power_up, stop_node, start_node);
* a repair of two devices off and two hung nodes among 2,000 (ten steps);
* a 10-step repair among 2,000 with paper 000's own STRIPS domain
  (benchmarks/data/paper_repair.pddl: no dependencies, quantifiers or conditional effects),
  to compare with the issue's anchor (Fast Downward 0.55-0.70 s for a 10-step repair among
  2,000 objects).

Ours is timed twice: *cold* (a new planner: ground the model, build the problem, search,
validate, deorder) and *warm* (the ground task cached, as the daemon keeps it: problem,
search, validate, deorder). Fast Downward is its own driver (translate + search) run on the
domain file and the problem file ``to_pddl`` writes, with ``astar(blind())`` (optimal, like
ours) and ``--alias lama-first`` (satisficing); wall time of the subprocess, with a time
limit. Medians of repeated runs; the ratio column is Fast Downward's best time over ours
(warm). Run: ``.venv/bin/python benchmarks/planning.py [--quick]`` (needs ``.[bench]``).
"""

from __future__ import annotations

import argparse
import random
import statistics
import sys
import tempfile
import time
from collections.abc import Callable
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from host.diagnosis.logic import Literal  # noqa: E402
from host.planning.domain import Domain, load_domain  # noqa: E402
from host.planning.downward import DownwardRun, driver_path, run_fast_downward  # noqa: E402
from host.repair.planner import RepairPlanner  # noqa: E402
from host.repair.problem import RepairModel  # noqa: E402

DOMAIN = ROOT / "models" / "tedusar" / "repair.pddl"
PAPER_DOMAIN = ROOT / "benchmarks" / "data" / "paper_repair.pddl"
FD_CONFIGS = {"fd astar(blind())": "astar(blind())", "fd lama-first": "--alias lama-first"}
FD_TIME_LIMIT = 30


def synthetic_model(n: int, seed: int = 1) -> RepairModel:
    rng = random.Random(seed)
    types: dict[str, str] = {}
    needs: dict[str, tuple[str, ...]] = {}
    devices = max(1, n // 4)
    for i in range(devices):
        types[f"dev{i}"] = "switchable"
        types[f"drv{i}"] = "driver"
        needs[f"drv{i}"] = (f"dev{i}",)
    earlier = [f"drv{i}" for i in range(devices)]
    for j in range(n - 2 * devices):
        name = f"node{j}"
        types[name] = "node"
        needs[name] = tuple(rng.sample(earlier, k=min(len(earlier), rng.randint(1, 2))))
        if rng.random() < 0.3:
            earlier.append(name)
    return RepairModel(f"synthetic{n}", types, needs)


def power_up_case(m: RepairModel) -> tuple[list[str], list[Literal]]:
    obs = [Literal(f"on({c})", False) for c, t in m.types.items() if t == "switchable"]
    obs += [Literal(f"running({c})", False) for c in m.types if m.is_node(c)]
    return list(m.types), obs


def single_fault_case(m: RepairModel) -> tuple[list[str], list[Literal]]:
    dev = f"dev{len([t for t in m.types.values() if t == 'switchable']) // 2}"
    return [dev], [Literal(f"on({dev})", False)]


def ten_step_case(m: RepairModel) -> tuple[list[str], list[Literal]]:
    return ["dev3", "dev7", "node5", "node9"], [
        Literal("on(dev3)", False), Literal("on(dev7)", False)]


def paper_ten_step_case(m: RepairModel) -> tuple[list[str], list[Literal]]:
    devices = ["dev3", "dev7", "dev11", "dev15"]
    return [*devices, "node5", "node9", "node13"], [Literal(f"on({d})", False) for d in devices]


def median_time(fn: Callable[[], object], repeats: int) -> float:
    times = []
    for _ in range(repeats):
        t = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t)
    return statistics.median(times)


def fd_time(domain: Domain, model: RepairModel, bad: list[str], obs: list[Literal],
            search: str, repeats: int) -> tuple[float | None, str]:
    """Median wall time of the driver, and a note: plan length, translate / search split."""
    planner = RepairPlanner(domain, model)  # the problem in the domain's own words
    text = planner.problem_pddl(planner.problem(bad, obs))
    runs: list[DownwardRun] = []
    with tempfile.TemporaryDirectory(prefix="dxboard-bench-") as tmp:
        path = Path(tmp) / "problem.pddl"
        path.write_text(text)
        for _ in range(repeats):
            try:
                runs.append(
                    run_fast_downward(domain.path, path, Path(tmp), search, FD_TIME_LIMIT))
            except TimeoutError:
                return None, ""
            except RuntimeError as exc:  # the driver gives up when the translator runs out
                return None, f" ({str(exc).split('|')[-2].strip()})"
    run = sorted(runs, key=lambda r: r.seconds)[len(runs) // 2]
    length = "no plan" if run.steps is None else f"{len(run.steps)} steps"
    split = ""
    if run.translate_seconds is not None and run.search_seconds is not None:
        split = f"; translate {fmt(run.translate_seconds)}, search {fmt(run.search_seconds)}"
    return run.seconds, f" ({length}{split})"


def fmt(seconds: float | None) -> str:
    if seconds is None:
        return f">{FD_TIME_LIMIT} s"
    return f"{seconds * 1000:.1f} ms" if seconds < 1 else f"{seconds:.2f} s"


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="fewer repeats, no 1,000 power-up")
    args = ap.parse_args()
    if driver_path() is None:
        print("Fast Downward is missing: pip install -e '.[bench]'", file=sys.stderr)
        return 2
    ours, paper = load_domain(DOMAIN), load_domain(PAPER_DOMAIN)
    Case = tuple[str, int, Callable[[RepairModel], tuple[list[str], list[Literal]]], Domain]
    cases: list[Case] = [
        ("power-up", 10, power_up_case, ours),
        ("power-up", 100, power_up_case, ours),
        ("power-up", 1000, power_up_case, ours),
        ("single fault", 100, single_fault_case, ours),
        ("single fault", 1000, single_fault_case, ours),
        ("single fault", 2000, single_fault_case, ours),
        ("10-step repair", 2000, ten_step_case, ours),
        ("paper domain: 10-step repair", 2000, paper_ten_step_case, paper),
    ]
    if args.quick:
        cases = [c for c in cases if not (c[0] == "power-up" and c[1] == 1000)]
    fd_repeats = 1 if args.quick else 3
    header = ["case", "N", "steps", "ours cold", "ours warm", *FD_CONFIGS, "FD best / ours warm"]
    print("| " + " | ".join(header) + " |")
    print("|" + "---|" * len(header))
    for label, n, make, domain in cases:
        model = synthetic_model(n)
        bad, obs = make(model)

        def cold(model: RepairModel = model, bad: list[str] = bad,
                 obs: list[Literal] = obs, domain: Domain = domain) -> object:
            return RepairPlanner(domain, model).plan(bad, obs)

        warm_planner = RepairPlanner(domain, model)
        plan = warm_planner.plan(bad, obs)
        repeats = 3 if n >= 1000 else 10
        t_cold = median_time(cold, 1 if args.quick else repeats)
        def warm(p: RepairPlanner = warm_planner, b: list[str] = bad,
                 o: list[Literal] = obs) -> object:
            return p.plan(b, o)

        t_warm = median_time(warm, repeats if args.quick else 3 * repeats)
        fd_cells = []
        fd_best: float | None = None
        for search in FD_CONFIGS.values():
            if "blind" in search and label.startswith("power-up") and n > 10:
                fd_cells.append("(not run: blind A* on 2^N states)")
                continue
            if "blind" in search and domain is paper:
                fd_cells.append("(not run: same translator as lama-first)")
                continue
            t, note = fd_time(domain, model, bad, obs, search, fd_repeats)
            cell = fmt(t) + note
            fd_cells.append(cell)
            if t is not None:
                fd_best = t if fd_best is None else min(fd_best, t)
        ratio = f"{fd_best / t_warm:.0f}x" if fd_best is not None else "-"
        row = [label, f"{n:,}", str(len(plan)), fmt(t_cold), fmt(t_warm), *fd_cells, ratio]
        print("| " + " | ".join(row) + " |", flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
