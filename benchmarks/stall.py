"""The daemon's loop while it diagnoses a large model: how long can the board link starve?

The daemon's event loop reads the board link (a reading every 10 ms at 100 Hz, a link deadline of
0.25 s); a diagnosis that runs on that loop stops it for as long as the search takes. The
daemon runs each diagnosis in a worker thread instead (``host.diagnosis.runner``). This measures
the loop's stalls with a 10,000-component synthetic robot (the generator of
``benchmarks/diagnosis.py``), every observer reporting, while observations change: each round
silences ``k`` random topics or devices at once (k = 1..4, harder searches as k grows) and
brings them back, diagnosing after every change with the daemon's bounds (no cardinality
bound, at most 20 diagnoses, 0.5 s budget). A ticker task on the same loop sleeps 1 ms at a
time and records how late it wakes: the loop's stall. Baseline, in the same run: the same
diagnoses called directly on the loop, as the daemon did before; and the loop with no diagnosis
at all for as long (*idle*): the machine's own floor, what the operating system's scheduler
alone costs the loop at the run's load. The worker thread is measured as the daemon ran it before
(*worker thread*) and as it runs it now (*frozen*): the model's objects moved out of the cyclic
collector's reach after start-up (``gc.freeze()``, as ``Daemon.start`` does), so that a full
collection, which holds the GIL and so stops the loop too, no longer walks the 10,000-component
model. *gc max*: the longest collection during the rounds (``gc.callbacks``), any thread.

    .venv/bin/python benchmarks/stall.py [--size N] [--rounds R] [--write]

``--write`` replaces the "## Loop stall during diagnosis" section of benchmarks/RESULTS.md.
"""

from __future__ import annotations

import argparse
import asyncio
import gc
import importlib.util
import os
import platform
import random
import re
import sys
import tempfile
import time
from collections.abc import Awaitable, Callable
from pathlib import Path

import yaml

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from host.diagnosis import Diagnoser, Literal, generate, load_system  # noqa: E402
from host.diagnosis.observations import Observation, ObservationSet  # noqa: E402
from host.diagnosis.runner import DiagnosisRunner  # noqa: E402

_spec = importlib.util.spec_from_file_location("bench_diagnosis",
                                               ROOT / "benchmarks" / "diagnosis.py")
assert _spec is not None and _spec.loader is not None
bench_diagnosis = importlib.util.module_from_spec(_spec)
sys.modules["bench_diagnosis"] = bench_diagnosis  # its dataclasses look their module up
_spec.loader.exec_module(bench_diagnosis)

BOUNDS = {"max_card": None, "max_count": 20, "time_budget_s": 0.5}


class Ticker:
    """Sleeps 1 ms at a time on the loop; records how late each wake-up is."""

    def __init__(self) -> None:
        self.lateness: list[float] = []
        self._task: asyncio.Task[None] | None = None

    async def _run(self) -> None:
        loop = asyncio.get_running_loop()
        while True:
            t = loop.time()
            await asyncio.sleep(0.001)
            self.lateness.append(loop.time() - t - 0.001)

    def __enter__(self) -> Ticker:
        self._task = asyncio.get_running_loop().create_task(self._run())
        return self

    def __exit__(self, *exc: object) -> None:
        assert self._task is not None
        self._task.cancel()


class GcPauses:
    """The longest cyclic collection while entered (``gc.callbacks``), in seconds."""

    def __init__(self) -> None:
        self.longest = 0.0
        self._start = 0.0

    def _callback(self, phase: str, info: dict[str, int]) -> None:
        if phase == "start":
            self._start = time.perf_counter()
        else:
            self.longest = max(self.longest, time.perf_counter() - self._start)

    def __enter__(self) -> GcPauses:
        gc.callbacks.append(self._callback)
        return self

    def __exit__(self, *exc: object) -> None:
        gc.callbacks.remove(self._callback)


async def idle(seconds: float) -> list[float]:
    """The loop's lateness with nothing but the ticker on it, for ``seconds``."""
    with Ticker() as ticker:
        await asyncio.sleep(seconds)
    return ticker.lateness


async def scenario(diagnose: Callable[[str], Awaitable[object]], obs: ObservationSet,
                   candidates: list[Literal], rounds: int, rng: random.Random
                   ) -> tuple[list[float], list[float]]:
    """Rounds of k observations silenced and restored; (loop lateness, diagnosis times)."""
    times: list[float] = []
    with Ticker() as ticker:
        await asyncio.sleep(0.05)
        for r in range(rounds):
            k = 1 + r % 4
            flipped = rng.sample(candidates, k)
            for lits in ([-x for x in flipped], flipped):
                for lit in lits:
                    obs.add(Observation(lit, time.monotonic(), "bench"))
                t0 = time.perf_counter()
                await diagnose("observation")
                times.append(time.perf_counter() - t0)
                await asyncio.sleep(0.005)  # the loop's own work between changes
    return ticker.lateness, times


def pct(xs: list[float], q: float) -> float:
    s = sorted(xs)
    return s[min(len(s) - 1, int(q * len(s)))]


def ms(x: float) -> str:
    return f"{x * 1000:.1f} ms"


async def run(size: int, rounds: int) -> list[str]:
    rng = random.Random(11)
    with tempfile.TemporaryDirectory() as tmp:
        (Path(tmp) / "system.yaml").write_text(
            yaml.safe_dump(bench_diagnosis.robot_yaml(size, rng)))
        theory = generate(load_system(tmp))
    healthy = bench_diagnosis.healthy_observations(theory)
    candidates = [o for o in healthy if o.positive]
    rows = []
    took = 0.0
    for label in ("on the loop (before)", "worker thread (before)", "worker thread, frozen (now)",
                  "idle (no diagnosis)"):
        if label.startswith("idle"):
            load = os.getloadavg()[0]
            lateness, times = await idle(took), []
            rows.append(f"| {label} | - | - | - | {ms(pct(lateness, 0.99))} | "
                        f"{ms(max(lateness))} | - | {load:.1f} |")
            print(rows[-1], flush=True)
            continue
        obs = ObservationSet()
        for lit in healthy:
            obs.add(Observation(lit, time.monotonic(), "bench"))
        d = Diagnoser(theory, observations=obs)
        d.diagnose(literals=obs.literals(), **BOUNDS)  # type: ignore[arg-type]
        if label.startswith("worker"):
            runner = DiagnosisRunner(d, obs, lambda e: None, **BOUNDS)  # type: ignore[arg-type]
            if "frozen" in label:
                gc.collect()
                gc.freeze()
            load = os.getloadavg()[0]
            start = time.perf_counter()
            with GcPauses() as pauses:
                lateness, times = await scenario(runner.run, obs, candidates, rounds,
                                                 random.Random(5))
            took = max(took, time.perf_counter() - start)
            runner.close()
            gc.unfreeze()
        else:
            async def direct(trigger: str, d: Diagnoser = d, obs: ObservationSet = obs) -> None:
                d.diagnose(literals=obs.literals(), **BOUNDS)  # type: ignore[arg-type]

            load = os.getloadavg()[0]
            with GcPauses() as pauses:
                lateness, times = await scenario(direct, obs, candidates, rounds,
                                                 random.Random(5))
            d.close()
        rows.append(f"| {label} | {len(times)} | {ms(pct(times, 0.5))} | {ms(max(times))} | "
                    f"{ms(pct(lateness, 0.99))} | {ms(max(lateness))} | {ms(pauses.longest)} | "
                    f"{load:.1f} |")
        print(rows[-1], flush=True)
    return [
        "## Loop stall during diagnosis\n",
        f"`benchmarks/stall.py`: a {size:,}-component synthetic robot ({len(theory.clauses):,} "
        f"clauses, {len(healthy):,} observations), {rounds} rounds of 1-4 observations "
        "silenced and restored, diagnosed after each change with the daemon's bounds (all "
        "minimal diagnoses up to 20, 0.5 s budget); a 1 ms ticker on the daemon's loop "
        f"records its stalls. {platform.python_version()}, one run.\n",
        "| diagnosis runs | diagnoses | diagnosis p50 | diagnosis max | loop stall p99 | "
        "loop stall max | gc max | load |",
        "|---|---|---|---|---|---|---|---|",
        *rows,
        "",
    ]


def write_results(section: list[str]) -> None:
    path = ROOT / "benchmarks" / "RESULTS.md"
    text = path.read_text()
    new = "\n".join(section) + "\n"
    pat = re.compile(r"^## Loop stall during diagnosis\n.*?(?=^## |\Z)", re.S | re.M)
    text = pat.sub(new, text) if pat.search(text) else text.rstrip("\n") + "\n\n" + new
    path.write_text(text)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--size", type=int, default=10000)
    ap.add_argument("--rounds", type=int, default=40)
    ap.add_argument("--write", action="store_true")
    args = ap.parse_args()
    section = asyncio.run(run(args.size, args.rounds))
    print("\n".join(section))
    if args.write:
        write_results(section)


if __name__ == "__main__":
    main()
