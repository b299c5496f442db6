"""The whole ``dxboard diagnose`` process against the engine alone (benchmarks/diagnosis.py's
``--only command``), and the timing helpers the diagnosis benchmarks share.

Per instance (a circuit written as a tug model file, every primary input and output observed),
the best of ``--repeat`` runs of each:

- *engine*: in the benchmark's process, the model loaded: ``Diagnoser(theory)`` built (it
  encodes the theory: variable numbers, numeric clauses, circuit structure), observations
  added, ``diagnose``. The baseline issue 17 item 5 is judged by.
- *engine, given the encoding*: the same, but given the theory's encoding as the command reads
  it from its cache (a fresh copy each run, so no run inherits another's memo), and the
  collector frozen as the command freezes it: the engine doing the work the warm command
  does, no more, with the same setting.
- *engine, fresh process*: a process of its own per run, the command's code path (the
  encoding read from the same cache, the collector frozen, the observations read), timed
  around the engine's own calls only: it separates what the command adds from a fresh
  process's colder search.
- *command (warm)*: ``dxboard diagnose MODEL --obs FILE --json --min-card-only``, its cache
  filled (before the circuit's first instance); *cold*: with an empty cache directory each time
  (it parses the YAML, encodes and writes the entry); *warm*: the same command handed to a warm
  server (``dxboard warm``), its CPU the console script's process plus the server's over the
  same span, its forked child's included (``benchmarks/_rigs/warm.py``); *before*: the command
  from the checkout ``--base`` names, interleaved with it.

CPU is user + system time (the command's whole process; the engine's calls in-process), which
the machine's load changes far less than wall time.
"""

from __future__ import annotations

import argparse
import copy
import gc
import json
import os
import random
import resource
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from benchmarks.iscas import ISCAS, circuit_theory, parse_bench, sample
from host.diagnosis import Diagnoser, DiagnosisResult, Literal, Theory
from host.diagnosis.encoding import Encoding, encode
from host.diagnosis.tug import write_tug

MAX_COUNT = 1000

#: the fresh-process engine: argv model, obs, budget; prints wall, CPU, cut_by (JSON)
FRESH_ENGINE = """\
import gc, json, sys, time
from host.diagnosis.diagnoser import Diagnoser
from host.diagnosis.files import load_encoded, read_observations
enc = load_encoded(sys.argv[1])
gc.freeze()
obs = read_observations(sys.argv[2], enc.theory)
t, c = time.perf_counter(), time.process_time()
with Diagnoser(enc.theory, encoding=enc) as d:
    for o in obs:
        d.observe(o)
    r = d.diagnose(min_card_only=True, max_count=1000, time_budget_s=float(sys.argv[3]))
t, c = time.perf_counter() - t, time.process_time() - c
print(json.dumps([t, c, r.cut_by and r.cut_by.value, len(r.diagnoses)]))
"""


def timed(fn, *args, **kw):  # type: ignore[no-untyped-def]
    t = time.perf_counter()
    r = fn(*args, **kw)
    return time.perf_counter() - t, r


def cpu_timed(fn, *args, **kw):  # type: ignore[no-untyped-def]
    """Wall time, this process's CPU time (what a machine of its own would have taken, near
    enough: the search is single-threaded) and the result."""
    c = time.process_time()
    t, r = timed(fn, *args, **kw)
    return t, time.process_time() - c, r


def fmt(s: float) -> str:
    return f"{s * 1000:.1f} ms" if s < 1 else f"{s:.2f} s"


def mean_worst(xs: list[float]) -> str:
    """Mean and worst; instances a budget cut (``inf``) are left out of the mean and make
    the worst read ``cut``."""
    done = [x for x in xs if x != float("inf")]
    if not xs:
        return "-"
    worst = "cut" if len(done) < len(xs) else fmt(max(done))
    return f"{fmt(statistics.fmean(done)) if done else '-'} / {worst}"


def _run_child(cmd: list[str], env: dict[str, str] | None = None) -> tuple[
        float, float, subprocess.CompletedProcess[str]]:
    """Wall and CPU time (user + system, from the children's usage) of one process."""
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    start = time.perf_counter()
    proc = subprocess.run(cmd, capture_output=True, text=True, check=False, env=env)
    wall = time.perf_counter() - start
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    return wall, (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime), proc


def _commands(args: argparse.Namespace) -> dict[str, list[str]]:
    """The command's argv prefix, and the base checkout's (``--base``) when given."""
    out = {"command": [str(Path(sys.executable).parent / "dxboard")]}
    if args.base:
        out["before"] = [sys.executable, "-c", "import sys; sys.path.insert(0, sys.argv.pop(1)); "
                         "from host.cli import main; sys.exit(main())", str(args.base)]
    return out


def _child_env(tmp: Path) -> dict[str, str]:
    """The commands' environment: a cache directory of their own (not the user's), and
    Python's bytecode kept (in ``tmp``) as an installed program has it, whatever
    ``PYTHONDONTWRITEBYTECODE`` says here: without it every run compiled dxboard's modules
    from source again (about 30 ms a run), which no user's install does."""
    env = {**os.environ, "XDG_CACHE_HOME": str(tmp / "cache"),
           "PYTHONPYCACHEPREFIX": str(tmp / "pycache"),
           "DXBOARD_WARM_SOCKET": str(tmp / "no-server.sock")}  # cold: no warm server
    env.pop("PYTHONDONTWRITEBYTECODE", None)
    return env


def _warm_model(theory: Theory, model: Path, env: dict[str, str]) -> Path:
    """``theory`` written as a tug model file, the command's cache filled with it (every run
    of the command on it is then warm)."""
    write_tug(theory, model)
    subprocess.run([sys.executable, "-c", "import sys; from host.diagnosis.files import "
                    "load_encoded; load_encoded(sys.argv[1])", str(model)], check=True, env=env)
    return model


def bench_startup(args: argparse.Namespace, lines: list[str], env: dict[str, str]) -> None:
    """``dxboard diagnose --help``: the interpreter, the imports, argparse; no model."""
    runs = 5 if args.quick else 20
    times: dict[str, list[float]] = {}
    for _ in range(runs):  # interleaved: the machine's load falls on both alike
        for label, prefix in _commands(args).items():
            wall, _cpu, proc = _run_child([*prefix, "diagnose", "--help"], env)
            assert proc.returncode == 0, proc.stderr
            times.setdefault(label, []).append(wall)
    said = "; ".join(f"{label} {fmt(statistics.median(xs))} (best {fmt(min(xs))})"
                     for label, xs in times.items())
    lines.append(f"Start-up, `dxboard diagnose --help`, median of {runs} runs: {said}.\n")
    print(lines[-1], flush=True)


def _engine(theory: Theory, obs: list[Literal], budget: float,
            encoding: Encoding | None = None) -> DiagnosisResult:
    with Diagnoser(theory, encoding=encoding) as d:
        for o in obs:
            d.observe(o)
        return d.diagnose(min_card_only=True, max_count=MAX_COUNT, time_budget_s=budget)


def _engine_as_command(theory: Theory, obs: list[Literal], budget: float,
                       encoding: Encoding) -> DiagnosisResult:
    """The engine as the command runs it: given the encoding, the collector frozen."""
    gc.freeze()
    try:
        return _engine(theory, obs, budget, encoding)
    finally:
        gc.unfreeze()


def _intro(args: argparse.Namespace, per: int) -> str:
    return (f"`dxboard diagnose MODEL.yaml --obs FILE --json --min-card-only` (all minimal-"
            f"cardinality diagnoses, up to {MAX_COUNT:,}) as a process on the circuit written "
            f"as a tug model file, {per} instances per circuit (seed {args.seed + 1}), the best "
            f"of {args.repeat} runs of each kind per instance (benchmarks/command_bench.py's "
            "docstring says what each is). *engine*: in process, `Diagnoser` built (it encodes "
            "the theory), observations added, diagnosed: the baseline; *given enc.*: the same "
            "given the encoding the warm command reads from its cache; *fresh*: the engine's "
            "calls timed in a process of their own per run (the command's code path); "
            "*command*: warm (its model cache filled); *cold*: an empty cache each run; "
            "*warm*: the command handed to a warm server (`dxboard warm`), its CPU the console "
            "script's plus the server's over the same span, its child's included; "
            f"*runs cut*: runs the time budget ({args.budget:g} s) cut, not compared; CPU: user "
            "+ system; every process with Python's bytecode kept, as an installed program has it"
            + ("; *before*: the command from the checkout `--base` names, run interleaved"
               if args.base else "") + ".\n")


def bench_command(args: argparse.Namespace, lines: list[str]) -> None:
    """The whole ``dxboard diagnose`` process against the engine alone, same instances."""
    rng = random.Random(args.seed + 1)
    names = ["c6288"] if args.quick else ["c6288", "c7552"]
    per = 3 if args.quick else 10
    commands = _commands(args)
    commands = {"command": commands["command"], "cold": commands["command"],
                "warm": commands["command"],
                **{k: v for k, v in commands.items() if k != "command"}}
    lines.append("### The whole command against the engine alone\n")
    lines.append(_intro(args, per))
    from benchmarks._rigs import warm

    with tempfile.TemporaryDirectory(prefix="dxboard-bench-") as tmp:
        dir_ = Path(tmp)
        env = _child_env(dir_)
        warm_env = {**env, "DXBOARD_WARM_SOCKET": str(dir_ / "warm.sock")}
        server = warm.start_server(commands["command"], warm_env)
        try:
            _command_rows(args, lines, names, per, commands, rng, env, warm_env, dir_)
        finally:
            warm.stop_server(server)
    lines.append("")


def _command_rows(args: argparse.Namespace, lines: list[str], names: list[str], per: int,
                  commands: dict[str, list[str]], rng: random.Random, env: dict[str, str],
                  warm_env: dict[str, str], tmp: Path) -> None:
    from benchmarks._rigs import warm

    before = "before, sum | before / engine | " if args.base else ""
    bench_startup(args, lines, env)
    lines.append(
        f"| circuit | engine, sum | given enc., sum | fresh, sum | command, sum | {before}"
        "**command / engine** | CPU, command / engine | CPU, command / given enc. | "
        "CPU, command / fresh | cold / engine | CPU, cold / engine | "
        "**CPU, warm / engine** | CPU, warm / given enc. | overhead per run, "
        "mean / worst | load | runs cut |")
    lines.append("|---|---|---|---|---|" + ("---|---|" if args.base else "") + "---|" * 11)
    colds = 0
    for name in names:
        circuit = parse_bench(ISCAS / f"{name}.bench")
        if args.circuits and name not in args.circuits:
            list(sample(circuit, rng, per))  # drawn all the same: the others' sample stays
            continue
        theory = circuit_theory(circuit)
        encoding = encode(theory, structure=True)  # as the cache holds it
        known = theory.observable_atoms()
        model = _warm_model(theory, tmp / f"{name}.yaml", env)
        labels = ["engine", "given", "fresh", *commands]
        wall: dict[str, list[float]] = {label: [] for label in labels}
        cpu: dict[str, list[float]] = {label: [] for label in labels}
        cut = 0
        loads = [os.getloadavg()[0]]
        for n, (_flips, obs) in enumerate(sample(circuit, rng, per)):
            obs = [o for o in obs if o.atom in known]
            obs_file = tmp / f"{name}-{n}.obs"
            obs_file.write_text("".join(f"{o}\n" for o in obs))
            runs = [cpu_timed(_engine, theory, obs, args.budget) for _ in range(args.repeat)]
            r = runs[0][2]
            wall["engine"].append(min(t for t, _c, _r in runs))
            cpu["engine"].append(min(c for _t, c, _r in runs))
            copies = [copy.deepcopy(encoding) for _ in range(args.repeat)]  # untimed
            runs = [cpu_timed(_engine_as_command, theory, obs, args.budget, e)
                    for e in copies]
            wall["given"].append(min(t for t, _c, _r in runs))
            cpu["given"].append(min(c for _t, c, _r in runs))
            for label, prefix in commands.items():
                best, best_cpu = float("inf"), float("inf")
                for _ in range(args.repeat):
                    run_env = env
                    if label == "cold":  # a cache directory of its own, empty
                        colds += 1
                        run_env = {**env, "XDG_CACHE_HOME": str(tmp / f"c{colds}")}
                    cmd = [*prefix, "diagnose", str(model), "--obs", str(obs_file),
                           "--json", "--min-card-only", "--time-budget", str(args.budget)]
                    if label == "warm":  # handed to the warm server: its CPU counted
                        t, c, proc = warm.run(cmd, warm_env, True)
                    else:
                        t, c, proc = _run_child(cmd, run_env)
                    best, best_cpu = min(best, t), min(best_cpu, c)
                    assert proc.returncode in (0, 1), proc.stderr  # 1: cut before the first
                    data = json.loads(proc.stdout)
                    if "time_budget" in (data["cut_by"], r.cut_by):
                        cut += 1  # the budget cut one of the two on a loaded machine
                        continue
                    if not data["complete"] or r.cut_by is not None:
                        continue  # 1,000 kept of more: not compared (ties at the edge)
                    assert sorted(map(tuple, (x["bad"] for x in data["diagnoses"]))) == (
                        sorted(tuple(sorted(x.bad)) for x in r.diagnoses))
                wall[label].append(best)
                cpu[label].append(best_cpu)
            fresh = []
            for _ in range(args.repeat):  # after the command: its cache entry is there
                proc = subprocess.run(
                    [sys.executable, "-c", FRESH_ENGINE, str(model), str(obs_file),
                     str(args.budget)], capture_output=True, text=True, check=True, env=env)
                t, c, cut_by, count = json.loads(proc.stdout)
                assert count == len(r.diagnoses) or "time_budget" in (cut_by, r.cut_by)
                fresh.append((t, c))
            wall["fresh"].append(min(t for t, _c in fresh))
            cpu["fresh"].append(min(c for _t, c in fresh))
            loads.append(os.getloadavg()[0])
        lines.append(_row(name, wall, cpu, args.base is not None, cut, loads))
        print(lines[-1], flush=True)


def _row(name: str, wall: dict[str, list[float]], cpu: dict[str, list[float]], base: bool,
         cut: int, loads: list[float]) -> str:
    w = {k: sum(v) for k, v in wall.items()}
    c = {k: sum(v) for k, v in cpu.items()}
    old = f"{fmt(w['before'])} | {w['before'] / w['engine']:.2f}x | " if base else ""
    overhead = [a - b for a, b in zip(wall["command"], wall["engine"], strict=True)]
    return (f"| {name} | {fmt(w['engine'])} | {fmt(w['given'])} | {fmt(w['fresh'])} | "
            f"{fmt(w['command'])} | {old}**{w['command'] / w['engine']:.2f}x** | "
            f"{c['command'] / c['engine']:.2f}x | {c['command'] / c['given']:.2f}x | "
            f"{c['command'] / c['fresh']:.2f}x | {w['cold'] / w['engine']:.2f}x | "
            f"{c['cold'] / c['engine']:.2f}x | **{c['warm'] / c['engine']:.2f}x** | "
            f"{c['warm'] / c['given']:.2f}x | {mean_worst(overhead)} | "
            f"{min(loads):.1f}-{max(loads):.1f} | {cut} |")


def bench_rc2_process(args: argparse.Namespace, lines: list[str]) -> None:
    """Issue 30 item 3: ``dxboard diagnose`` as a process against PySAT's RC2 run as a
    process (``python -m pysat.examples.rc2 FILE.wcnf``, first optimum) on the same CNF
    (hard: the circuit's clauses and the observations; soft: each gate healthy), c2670 and
    c7552: the command's first minimum (``--min-card-only --max-count 1``) and its whole
    minimal-cardinality list (``--min-card-only``, up to 1,000); CPU of the whole process
    (user + system), the best of ``--repeat`` runs, the command's cache warm. Beside them the
    same two commands handed to a warm server (``dxboard warm``): the console script's process
    plus the server's CPU meanwhile, its forked child's included
    (``benchmarks/_rigs/warm.py``)."""
    from benchmarks._rigs import warm

    rng = random.Random(args.seed + 2)
    per = 3 if args.quick else 5
    command = _commands(args)["command"]
    lines.append("### The whole command against RC2 as a process, same CNF\n")
    lines.append(f"{per} instances per circuit (seed {args.seed + 2}), the best of "
                 f"{args.repeat} runs each, CPU time (user + system) of the whole process, "
                 "summed; the command's cache warm. *first*: `dxboard diagnose MODEL --obs "
                 "FILE --json --min-card-only --max-count 1`; *all*: the same without "
                 "`--max-count 1` (every minimal-cardinality diagnosis, up to 1,000); RC2: "
                 "`python -m pysat.examples.rc2 FILE.wcnf` (its first optimum). Load average "
                 f"{os.getloadavg()[0]:.1f} at the start.\n")
    lines.append("| circuit | RC2 process | command, first | command, all | first / RC2 | "
                 "all / RC2 | warm: first | warm: all | warm first / RC2 | warm all / RC2 | "
                 "load |")
    lines.append("|---|---|---|---|---|---|---|---|---|---|---|")
    with tempfile.TemporaryDirectory(prefix="dxboard-bench-") as tmp:
        env = _child_env(Path(tmp))
        warm_env = {**env, "DXBOARD_WARM_SOCKET": str(Path(tmp) / "warm.sock")}
        server = warm.start_server(command, warm_env)
        try:
            _rc2_rows(args, lines, command, env, warm_env, Path(tmp), rng, per)
        finally:
            warm.stop_server(server)
    lines.append("")


def _rc2_rows(args: argparse.Namespace, lines: list[str], command: list[str],
              env: dict[str, str], warm_env: dict[str, str], tmp: Path, rng: random.Random,
              per: int) -> None:
    from benchmarks._rigs import warm
    from benchmarks.iscas import _wcnf

    for name in ("c2670", "c7552"):
        circuit = parse_bench(ISCAS / f"{name}.bench")
        if args.circuits and name not in args.circuits:
            continue
        theory = circuit_theory(circuit)
        known = theory.observable_atoms()
        model = _warm_model(theory, tmp / f"{name}.yaml", env)
        cpu: dict[str, float] = {"rc2": 0.0, "first": 0.0, "all": 0.0, "warm first": 0.0,
                                 "warm all": 0.0}
        loads = [os.getloadavg()[0]]
        for n, (_flips, obs) in enumerate(sample(circuit, rng, per)):
            obs = [o for o in obs if o.atom in known]
            obs_file = tmp / f"{name}-{n}.obs"
            obs_file.write_text("".join(f"{o}\n" for o in obs))
            wcnf_file = tmp / f"{name}-{n}.wcnf"
            _wcnf(theory, obs)[0].to_file(str(wcnf_file))
            base = [*command, "diagnose", str(model), "--obs", str(obs_file), "--json",
                    "--min-card-only", "--time-budget", str(args.budget)]
            runs = {"rc2": [sys.executable, "-m", "pysat.examples.rc2", str(wcnf_file)],
                    "first": [*base, "--max-count", "1"], "all": base,
                    "warm first": [*base, "--max-count", "1"], "warm all": base}
            costs: dict[str, int] = {}
            for label, cmd in runs.items():
                best = float("inf")
                hot = label.startswith("warm")
                for _ in range(args.repeat):
                    _t, c, proc = warm.run(cmd, warm_env if hot else env, hot)
                    best = min(best, c)
                    if label == "rc2":
                        costs[label] = int(next(line.split()[1] for line in
                                                proc.stdout.splitlines()
                                                if line.startswith("o ")))
                    else:
                        data = json.loads(proc.stdout)
                        costs[label] = data["diagnoses"][0]["cardinality"]
                cpu[label] += best
            assert len(set(costs.values())) == 1, costs  # the same minimum everywhere
            loads.append(os.getloadavg()[0])
        lines.append(f"| {name} | {fmt(cpu['rc2'])} | {fmt(cpu['first'])} | "
                     f"{fmt(cpu['all'])} | {cpu['first'] / cpu['rc2']:.2f}x | "
                     f"{cpu['all'] / cpu['rc2']:.2f}x | {fmt(cpu['warm first'])} | "
                     f"{fmt(cpu['warm all'])} | {cpu['warm first'] / cpu['rc2']:.2f}x | "
                     f"{cpu['warm all'] / cpu['rc2']:.2f}x | "
                     f"{min(loads):.1f}-{max(loads):.1f} |")
        print(lines[-1], flush=True)
