"""Fast Downward as a pluggable planner: its own driver on our PDDL files.

The PyPI package ``up-fast-downward`` (optional extra ``bench``) ships the Fast Downward
driver (``downward/fast-downward.py``) and the compiled ``downward`` search binary. This
module writes the problem next to the domain file's path in a temporary directory, runs the
driver directly (not through unified-planning) with ``--plan-file`` and a search
configuration (default ``astar(blind())``: optimal, and it accepts conditional effects,
which LM-cut does not), and maps the plan's lines ``(power_up jaguar)`` back to the ground
operators of our task. An operator the task lacks (one the protection layer removed) is an
error. ``driver_path()`` is None when the package is not installed.
"""

from __future__ import annotations

import importlib.util
import logging
import re
import sys
import time
from dataclasses import dataclass
from pathlib import Path

from host.errors import UserError
from host.planning.errors import NoPlanError
from host.planning.search import SearchInput, SearchResult

log = logging.getLogger(__name__)

DEFAULT_SEARCH = "astar(blind())"
NO_PLAN_EXIT_CODES = (11, 12)  # search: unsolvable, unsolvable incomplete
OUT_OF_TIME_EXIT_CODES = (23,)  # search out of time (--overall-time-limit)


def driver_path() -> Path | None:
    spec = importlib.util.find_spec("up_fast_downward")
    if spec is None or not spec.submodule_search_locations:
        return None
    path = Path(next(iter(spec.submodule_search_locations))) / "downward" / "fast-downward.py"
    return path if path.exists() else None


@dataclass(frozen=True)
class DownwardRun:
    """One run of the driver: the plan as (action, args) pairs (None: proven unsolvable),
    the wall time of the whole run, and what Fast Downward reports for its two phases."""

    steps: list[tuple[str, tuple[str, ...]]] | None
    seconds: float
    translate_seconds: float | None
    search_seconds: float | None


def _reported(pattern: str, text: str) -> float | None:
    m = re.search(pattern, text)
    return float(m.group(1)) if m else None


def run_fast_downward(
    domain: Path, problem: Path, workdir: Path, search: str = DEFAULT_SEARCH, time_limit: int = 300
) -> DownwardRun:
    """Run the driver on two PDDL files in ``workdir``.

    Fast Downward stops itself after ``time_limit`` seconds (``TimeoutError`` then)."""
    driver = driver_path()
    if driver is None:
        raise UserError(
            "Fast Downward is not installed",
            "pip install 'dxboard[bench]' (the up-fast-downward package)",
        )
    plan_file = workdir / "plan.txt"
    cmd = [sys.executable, str(driver), "--overall-time-limit", f"{time_limit}s",
           "--plan-file", str(plan_file), str(domain), str(problem)]
    if search.startswith("--alias"):
        cmd[4:4] = search.split()
    else:
        cmd += ["--search", search]
    import subprocess  # here: a planner that never runs FD (every command's) need not load it

    start = time.perf_counter()
    proc = subprocess.run(cmd, cwd=workdir, capture_output=True, text=True)
    elapsed = time.perf_counter() - start
    if proc.returncode in OUT_OF_TIME_EXIT_CODES:
        raise TimeoutError(f"fast-downward ran out of its {time_limit} s")
    translate = _reported(r"Done! \[[\d.]+s CPU, ([\d.]+)s wall-clock\]", proc.stdout)
    search_s = _reported(r"\] Total time: ([\d.]+)s", proc.stdout)
    if proc.returncode in NO_PLAN_EXIT_CODES:
        return DownwardRun(None, elapsed, translate, search_s)
    if proc.returncode != 0 or not plan_file.exists():
        tail = (proc.stdout + proc.stderr).strip().splitlines()[-3:]
        raise RuntimeError(f"fast-downward failed (exit {proc.returncode}): {' | '.join(tail)}")
    steps = []
    for line in plan_file.read_text().splitlines():
        line = line.strip()
        if line.startswith("(") and line.endswith(")"):
            name, *args = line[1:-1].split()
            steps.append((name, tuple(args)))
    return DownwardRun(steps, elapsed, translate, search_s)


def fast_downward(inp: SearchInput, search: str = DEFAULT_SEARCH) -> SearchResult:
    """The ``fast-downward`` entry of the planner registry."""
    if inp.domain_path is None or inp.problem_pddl is None:
        raise ValueError("fast-downward needs the domain file and the problem text")
    import tempfile

    with tempfile.TemporaryDirectory(prefix="dxboard-fd-") as tmp:
        problem = Path(tmp) / "problem.pddl"
        problem.write_text(inp.problem_pddl)
        run = run_fast_downward(inp.domain_path, problem, Path(tmp), search)
    steps, elapsed = run.steps, run.seconds
    if steps is None:
        return SearchResult(None, {"seconds": elapsed})
    by_name = {(op.name.lower(), tuple(a.lower() for a in op.args)): i
               for i, op in enumerate(inp.task.ops)}
    ops = []
    for name, args in steps:
        i = by_name.get((name.lower(), args))
        if i is None:
            raise NoPlanError(
                f"fast-downward planned ({name} {' '.join(args)}), which the problem layer "
                "forbids (it switches off a protected component)",
                "add (not (protected ?c)) to that action in the domain, or use --planner astar",
            )
        ops.append(i)
    return SearchResult(ops, {"seconds": elapsed})
