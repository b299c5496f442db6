"""Everyday commands against a bare interpreter's start: whole process against whole process.

Issue 30 item 2: ``dxboard plan models/tedusar --bad jaguar``, ``dxboard diagnose`` (its
start-up: the TEDUSAR model and a one-literal observation file), ``dxboard model check
models/tedusar`` and ``dxboard explain`` on a 50-step history should each cost at most twice
``python -c pass`` started the same way (the same interpreter, ``site`` and environment,
compiled modules cached as an installed package has them). Each is run as a process of its
own through the installed console script, ``--repeat`` times, interleaved with the baseline so
that the machine's load falls on both alike; CPU is the child's user + system time
(``RUSAGE_CHILDREN``), which load changes far less than wall time. Both sides inherit
``_ROS_WHEELS_BOOTSTRAP_COMPLETE`` from this process when it is set (as every child of a
bootstrapped Python does), so neither pays the ROS wheels' re-exec; ``--from-shell`` clears it,
so that both pay it, as a command typed in a shell does.

Beside them, Fast Downward's whole ``--alias lama-first`` command (its driver, translator and
search: ``host.planning.downward.run_fast_downward``, as benchmarks/planning.py runs it) on the
problem files ``dxboard plan --write-problem`` writes for the same diagnosis (``repair.pddl`` and
the problem), when ``up-fast-downward`` is installed (``pip install -e '.[bench]'``).

``--base DIR`` adds each command run from another checkout (``PYTHONPATH=DIR``, e.g. ``git
archive main | tar -x -C DIR``), interleaved too: before against after in the same run.

``--warm`` adds each command handed to a warm server (``dxboard warm start --foreground``, on a
socket of the run's own; docs/operating/warm.md), interleaved too. Its CPU is the console
script's process plus what the server spent meanwhile, its forked child's included (the
server's ``cpu_s`` and ``children_cpu_s`` from ``warm status`` before and after, which also
counts answering that status: the figure errs high). The cold commands look for a server at a
path where none listens, as a person's do who started none.

    python -m benchmarks.startup [--repeat 15] [--from-shell] [--base DIR] [--warm]
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import shutil
import statistics
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
if str(ROOT) not in sys.path:
    sys.path.insert(0, str(ROOT))

from benchmarks._rigs import warm as warm_rig  # noqa: E402 (the checkout on the path first)

FD = "fast-downward --alias lama-first (same problem files)"


def _run(cmd: list[str], env: dict[str, str], warm: bool = False) -> tuple[float, float]:
    """Wall and CPU seconds of one command; it must succeed (``warm``: ``_rigs.warm.run``)."""
    wall, cpu, proc = warm_rig.run(cmd, env, warm, cwd=ROOT)
    if proc.returncode != 0:
        raise SystemExit(f"{' '.join(cmd)}: exit {proc.returncode}: {proc.stderr[-400:]}")
    return wall, cpu


def _run_fd(domain: Path, problem: Path, workdir: Path) -> tuple[float, float]:
    """Wall and CPU seconds of Fast Downward's whole lama-first command (its driver and the
    translator and search processes the driver starts and waits for)."""
    from host.planning.downward import run_fast_downward

    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    start = time.perf_counter()
    run = run_fast_downward(domain, problem, workdir, "--alias lama-first", 60)
    wall = time.perf_counter() - start
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    if not run.steps:
        raise SystemExit(f"fast-downward found no plan for {problem}")
    return wall, (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)


def fifty_step_history(where: Path) -> Path:
    """A 50-step mission history needing one fault, with its domain (benchmarks/plandiag.py's
    case of 2 fault modes per action and 3 event types)."""
    from benchmarks._rigs.synth import synthetic_domain
    from benchmarks.plandiag import find_case

    case = find_case(2, 3, 50)
    mission, faults = synthetic_domain(11, modes=2, events=3)
    (where / "mission.pddl").write_text(mission)
    (where / "faults.pddl").write_text(faults)
    (where / "history.json").write_text(json.dumps(case.history.to_json()))
    return where / "history.json"


def commands(tmp: Path) -> dict[str, list[str]]:
    script = shutil.which("dxboard", path=str(Path(sys.executable).parent)) or "dxboard"
    dx = [sys.executable, script]
    obs = tmp / "jaguar.obs"
    obs.write_text("~on(jaguar)\n")
    history = fifty_step_history(tmp)
    return {
        "python -c pass": [sys.executable, "-c", "pass"],
        "plan models/tedusar --bad jaguar": [*dx, "plan", "models/tedusar", "--bad", "jaguar"],
        "diagnose models/tedusar --obs (1 literal)": [*dx, "diagnose", "models/tedusar",
                                                      "--obs", str(obs)],
        "model check models/tedusar": [*dx, "model", "check", "models/tedusar"],
        "explain (50-step history)": [*dx, "explain", str(history), str(tmp)],
    }


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--repeat", type=int, default=15)
    parser.add_argument("--from-shell", action="store_true",
                        help="clear the ROS wheels' guard: both sides pay the re-exec")
    parser.add_argument("--base", metavar="DIR", help="also run each command from this checkout")
    parser.add_argument("--warm", action="store_true",
                        help="also run each command through a warm server")
    args = parser.parse_args()
    env = dict(os.environ)
    if args.from_shell:
        env.pop("_ROS_WHEELS_BOOTSTRAP_COMPLETE", None)
    with tempfile.TemporaryDirectory(prefix="dxboard-startup-") as t:
        # compiled modules kept, as an installed dxboard has them (pip compiles on install),
        # in a directory of the run's own so that the checkout stays clean
        env.pop("PYTHONDONTWRITEBYTECODE", None)
        env["PYTHONPYCACHEPREFIX"] = str(Path(t) / "pycache")
        env["DXBOARD_WARM_SOCKET"] = str(Path(t) / "no-server.sock")
        cmds = commands(Path(t))
        from host.planning.downward import driver_path

        fd_problem = Path(t) / "jaguar-problem.pddl" if driver_path() is not None else None
        if fd_problem is not None:
            _run([*cmds["plan models/tedusar --bad jaguar"], "--write-problem", str(fd_problem)],
                 env)
        envs = {name: env for name in cmds}
        if args.base:
            base_env = dict(env, PYTHONPATH=str(Path(args.base).resolve()),
                            XDG_CACHE_HOME=str(Path(t) / "base-cache"),
                            PYTHONPYCACHEPREFIX=str(Path(t) / "base-pycache"))
            for name in [n for n in cmds if n != "python -c pass"]:
                cmds[f"{name} (before: --base)"] = cmds[name]
                envs[f"{name} (before: --base)"] = base_env
        server = None
        if args.warm:
            warm_env = dict(env, DXBOARD_WARM_SOCKET=str(Path(t) / "warm.sock"))
            server = warm_rig.start_server(cmds["plan models/tedusar --bad jaguar"][:2],
                                           warm_env)
            for name in [n for n in cmds if n != "python -c pass" and "--base" not in n]:
                cmds[f"{name} (warm)"] = cmds[name]
                envs[f"{name} (warm)"] = warm_env
        try:
            wall, cpu, load = _measure(cmds, envs, args.repeat, fd_problem, Path(t))
        finally:
            if server is not None:
                warm_rig.stop_server(server)
    _print(args, wall, cpu, load)
    return 0


def _measure(cmds: dict[str, list[str]], envs: dict[str, dict[str, str]], repeat: int,
             fd_problem: Path | None, tmp: Path,
             ) -> tuple[dict[str, list[float]], dict[str, list[float]], list[float]]:
    """``repeat`` interleaved runs of every command (after one to warm the caches)."""
    for name, cmd in cmds.items():  # warm the file cache, the .pyc files, the caches
        _run(cmd, envs[name], name.endswith("(warm)"))
    wall: dict[str, list[float]] = {k: [] for k in cmds}
    cpu: dict[str, list[float]] = {k: [] for k in cmds}
    load = [os.getloadavg()[0]]
    for _ in range(repeat):
        for name, cmd in cmds.items():
            w, c = _run(cmd, envs[name], name.endswith("(warm)"))
            wall[name].append(w)
            cpu[name].append(c)
        if fd_problem is not None:
            w, c = _run_fd(ROOT / "models/tedusar/repair.pddl", fd_problem, tmp)
            wall.setdefault(FD, []).append(w)
            cpu.setdefault(FD, []).append(c)
        load.append(os.getloadavg()[0])
    return wall, cpu, load


def _print(args: argparse.Namespace, wall: dict[str, list[float]],
           cpu: dict[str, list[float]], load: list[float]) -> None:
    base_cpu = statistics.median(cpu["python -c pass"])
    base_wall = statistics.median(wall["python -c pass"])
    print(f"{args.repeat} interleaved runs each, load average {min(load):.1f}-{max(load):.1f}, "
          f"{'ROS re-exec paid by both' if args.from_shell else 'no ROS re-exec'}")
    print("| command | CPU median (best) | x bare CPU | wall median (best) | x bare wall |")
    print("|---|---|---|---|---|")
    for name in cpu:
        c, w = cpu[name], wall[name]
        print(f"| `{name}` | {statistics.median(c) * 1e3:.0f} ms ({min(c) * 1e3:.0f}) | "
              f"{statistics.median(c) / base_cpu:.2f}x | {statistics.median(w) * 1e3:.0f} ms "
              f"({min(w) * 1e3:.0f}) | {statistics.median(w) / base_wall:.2f}x |")
    if FD in cpu:
        ours = "plan models/tedusar --bad jaguar"
        print(f"\nFast Downward's whole command / dxboard plan's whole command: CPU "
              f"{statistics.median(cpu[FD]) / statistics.median(cpu[ours]):.2f}x, wall "
              f"{statistics.median(wall[FD]) / statistics.median(wall[ours]):.2f}x")
    else:
        print("\nFast Downward is not installed: pip install -e '.[bench]'")


if __name__ == "__main__":
    sys.exit(main())
