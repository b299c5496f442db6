"""Plan-execution diagnosis: SAT against the context tree, naive enumeration and K*, in one run.

Random mission domains (``benchmarks/_rigs/synth.py``: 4 actions, 1-3 fault modes each, 1-5
exogenous event types) and histories of 10-500 executed actions on 8 objects in which one or
two faults really happened and the last step's expected-state check saw the world; the first
seed whose history needs at least one fault to be explained is used. Per history:

* ``sat``: every minimal diagnosis (up to 3 faults, no count limit) of the whole history by
  the SAT engine, including what it costs to get there from the journal's history (alarm
  handler, context & plan interpreter, symptoms, fault region): the figure the targets are
  about. Median of 5 runs after an untimed one (the engine warm, as in a daemon); wall time
  (``sat``) and this thread's CPU time (``sat CPU``: the engine is single-threaded, so on a
  loaded machine it says what the engine costs).
* ``tree`` and ``naive``: the same search by the context tree and by naive enumeration (every
  fault set by size, each simulated), once, cut at ``BUDGET`` seconds (">" then); naive up to
  50 steps only.
* ``k*``: diagnosis as planning (``plandiag_kstar.py``): the history as a planning task for the
  top-quality planner K* (``kstar-planner``), all plans of least cost = the minimum-cardinality
  diagnoses only (less than the engines list); wall time of encoding and the subprocess.
* ``explain``: the whole ``dxboard explain HISTORY DOMAIN_DIR --max-card 3 --max-count 100000
  --no-region --json`` process on the same history and domain files (read, compile, SAT,
  print), median of 3: the whole-process figure to hold against K*'s whole process (its
  encoding and its subprocess), where ``sat`` is the warm engine's (issue 30: never mixed).
  CPU time (user + system, the processes' own and their children's), which the machine's
  load changes far less than wall time: ``k* CPU``, ``explain CPU`` and their ratio.
* the fault region's pruning: context-tree nodes expanded in the region's universe against
  the whole history's (the same diagnoses: the tests check the region's are among them).

The ratio columns are the baseline's time over SAT's in the same run. Run:
``.venv/bin/python benchmarks/plandiag.py [--quick] [--sizes 50 500] [--planner-up-to STEPS]
[--planner-timeout S]`` (K* needs ``.[bench]``; by default only up to 50 steps).
"""

from __future__ import annotations

import argparse
import importlib.util
import json
import os
import resource
import statistics
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from benchmarks._rigs.synth import (  # noqa: E402
    synthetic_domain,
    synthetic_history,
    synthetic_model,
)
from benchmarks.plandiag_kstar import minimum_diagnoses  # noqa: E402
from host.diagnosis.result import Bound  # noqa: E402
from host.plandiag.context import Context, interpret_context  # noqa: E402
from host.plandiag.engines import ENGINES  # noqa: E402
from host.plandiag.history import History  # noqa: E402
from host.plandiag.interpret import (  # noqa: E402
    handle_alarm,
    identify_symptoms,
    sensor_interpreter,
)
from host.plandiag.limits import ExplainOutcome, Limits  # noqa: E402
from host.plandiag.model import PlanModel  # noqa: E402
from host.plandiag.region import Region, fault_region  # noqa: E402

BUDGET = 20.0
KSTAR_TIMEOUT = 300
CONFIGS = [(1, 1), (2, 3), (3, 5)]  # (fault modes per action, event types)


@dataclass
class Case:
    modes: int
    events: int
    steps: int
    history: History
    model: PlanModel


def compile_history(model: PlanModel, history: History) -> tuple[Context, Region]:
    h, _ = handle_alarm(history)
    ctx = interpret_context(model, h, sensor_interpreter(model, h.components))
    return ctx, fault_region(ctx, identify_symptoms(ctx, h))


def find_case(modes: int, events: int, steps: int) -> Case:
    model = synthetic_model(11, modes=modes, events=events)
    for seed in range(200):
        gen = synthetic_history(model, steps=steps, objects=8, seed=1000 * steps + seed,
                                fault_rate=0.05, event_rate=0.01, realistic=False,
                                final_obs=20)
        if len(gen.history.steps) != steps:
            continue
        ctx, _ = compile_history(model, gen.history)
        out = ENGINES["sat"](ctx.problem, None, Limits(max_card=1, max_count=1))
        if out.diagnoses and out.diagnoses[0]:
            return Case(modes, events, steps, gen.history, model)
    raise SystemExit(f"no history of {steps} steps needing a fault ({modes}, {events})")


def timed(engine: str, ctx: Context, universe: frozenset[int] | None,
          limits: Limits) -> tuple[ExplainOutcome, float]:
    start = time.perf_counter()
    out = ENGINES[engine](ctx.problem, universe, limits)
    return out, time.perf_counter() - start


def _cpu() -> float:
    own = resource.getrusage(resource.RUSAGE_SELF)
    kids = resource.getrusage(resource.RUSAGE_CHILDREN)
    return own.ru_utime + own.ru_stime + kids.ru_utime + kids.ru_stime


def explain_whole(case: Case) -> float:
    """Median CPU time of the whole ``dxboard explain`` process on the case's files."""
    with tempfile.TemporaryDirectory(prefix="dxboard-plandiag-") as tmp:
        mission, faults = synthetic_domain(11, modes=case.modes, events=case.events)
        (Path(tmp) / "mission.pddl").write_text(mission)
        (Path(tmp) / "faults.pddl").write_text(faults)
        history = Path(tmp) / "history.json"
        history.write_text(json.dumps(case.history.to_json()))
        cmd = [sys.executable, "-m", "host.cli", "explain", str(history), tmp, "--max-card",
               "3", "--max-count", "100000", "--no-region", "--json"]
        # compiled modules kept, as an installed dxboard has them, in the run's own directory
        env = {k: v for k, v in os.environ.items() if k != "PYTHONDONTWRITEBYTECODE"}
        env["PYTHONPYCACHEPREFIX"] = str(Path(tmp) / "pycache")
        times = []
        for _ in range(4):  # the first fills the caches, as any earlier run would
            start = _cpu()
            subprocess.run(cmd, cwd=ROOT, capture_output=True, check=True, env=env)
            times.append(_cpu() - start)
    return statistics.median(times[1:])


def fmt(seconds: float | None, cut: bool = False) -> str:
    if seconds is None:
        return "-"
    text = f"{seconds * 1000:.1f} ms" if seconds < 1 else f"{seconds:.2f} s"
    return "> " + text if cut else text


def ratio(base: float | None, ours: float, cut: bool = False) -> str:
    if base is None:
        return "-"
    return f"{'> ' if cut else ''}{base / ours:.0f}x"


def run_case(case: Case, with_planner: bool, planner_timeout: int = KSTAR_TIMEOUT
             ) -> dict[str, str]:
    limits = Limits(max_card=3, max_count=None, time_budget_s=BUDGET)
    sat_times = []
    sat_cpu = []
    ctx, _ = compile_history(case.model, case.history)  # warm: the engine's modules loaded,
    timed("sat", ctx, None, limits)  # as in a daemon that has diagnosed before (untimed)
    for _ in range(5):
        start = time.perf_counter()
        cpu = time.thread_time()
        ctx, region = compile_history(case.model, case.history)
        sat, _ = timed("sat", ctx, None, limits)
        sat_times.append(time.perf_counter() - start)
        sat_cpu.append(time.thread_time() - cpu)
    t_sat = statistics.median(sat_times)
    row = {"history": f"{case.steps} steps, {case.modes} modes, {case.events} events",
           "faults": str(len(ctx.problem.faults)), "diagnoses": str(len(sat.diagnoses)),
           "sat": fmt(t_sat), "sat CPU": fmt(statistics.median(sat_cpu))}
    tree, t_tree = timed("tree", ctx, None, limits)
    late = tree.cut_by is Bound.TIME_BUDGET
    row["tree"] = fmt(t_tree, late)
    row["tree/sat"] = ratio(t_tree, t_sat, late)
    agree = late or set(tree.diagnoses) == set(sat.diagnoses)
    if case.steps <= 50:
        naive, t_naive = timed("naive", ctx, None, limits)
        late = naive.cut_by is Bound.TIME_BUDGET
        row["naive/sat"] = ratio(t_naive, t_sat, late)
        agree &= late or set(naive.diagnoses) == set(sat.diagnoses)
    else:
        row["naive/sat"] = "-"
    if with_planner:
        k = min(map(len, sat.diagnoses))
        cpu0 = _cpu()
        plans = minimum_diagnoses(ctx.problem, planner_timeout)
        t_kstar_cpu = _cpu() - cpu0
        row["k*"] = fmt(plans.seconds, plans.timed_out)
        row["k*/sat"] = ratio(plans.seconds, t_sat, plans.timed_out)
        t_explain = explain_whole(case)
        row["k* CPU"] = fmt(t_kstar_cpu, plans.timed_out)
        row["explain CPU"] = fmt(t_explain)
        row["k*/explain CPU"] = ratio(t_kstar_cpu, t_explain, plans.timed_out)
        agree &= plans.timed_out or plans.diagnoses == {d for d in sat.diagnoses if len(d) == k}
    else:
        row["k*"] = row["k*/sat"] = row["k* CPU"] = row["explain CPU"] = "-"
        row["k*/explain CPU"] = "-"
    in_region, _ = timed("tree", ctx, region.suspects, limits)
    row["nodes: region / all"] = f"{in_region.nodes} / {tree.nodes}"
    row["agree"] = "yes" if agree else "NO"
    return row


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="10 and 50 steps only")
    parser.add_argument("--no-planner", action="store_true", help="leave K* out")
    parser.add_argument("--sizes", type=int, nargs="+", default=None,
                        help="history lengths (steps) to run (default: 10 50 100 500)")
    parser.add_argument("--planner-up-to", type=int, default=50, metavar="STEPS",
                        help="run K* on histories of at most this many steps (default 50)")
    parser.add_argument("--planner-timeout", type=int, default=KSTAR_TIMEOUT, metavar="S",
                        help=f"K*'s time limit per history, s (default {KSTAR_TIMEOUT})")
    args = parser.parse_args()
    if not args.no_planner and importlib.util.find_spec("kstar_planner") is None:
        print("plandiag: K* (kstar-planner) is not installed: `.venv/bin/pip install -e '.[bench]'`"
              ", or leave it out with --no-planner", file=sys.stderr)
        return 2
    sizes = args.sizes or ([10, 50] if args.quick else [10, 50, 100, 500])
    rows = []
    print(f"load average {os.getloadavg()[0]:.1f} at the start", file=sys.stderr, flush=True)
    for steps in sizes:
        for modes, events in CONFIGS:
            case = find_case(modes, events, steps)
            row = run_case(case, not args.no_planner and steps <= args.planner_up_to,
                           args.planner_timeout)
            row["load"] = f"{os.getloadavg()[0]:.1f}"
            rows.append(row)
            print(" | ".join(row.values()), file=sys.stderr, flush=True)
    cols = list(rows[0])
    print("| " + " | ".join(cols) + " |")
    print("|" + "---|" * len(cols))
    for row in rows:
        print("| " + " | ".join(row[c] for c in cols) + " |")
    return 0 if all(r["agree"] == "yes" for r in rows) else 1


if __name__ == "__main__":
    raise SystemExit(main())
