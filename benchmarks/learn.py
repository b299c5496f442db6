"""Learn the virtual TEDUSAR robot's model, then diagnose the fault campaign with it and with the
hand-written one (issue 28, item 3).

    .venv/bin/python -m benchmarks.learn [--duration 60] [--singles 6] [--doubles 2]
        [--quiet-s 60] [--seed 1] [--keep DIR | --learned DIR] [--trials I,J,...]
        [--models written,learned] [--work DIR]

``--keep DIR`` keeps the learned model (DIR must not hold a ``system.yaml`` yet);
``--learned DIR`` skips step 1 and uses the model a run kept there; ``--trials`` plays only
those trials of the seeded plan (by index, as printed) and ``--models`` only those models: a
re-run of the trials that differed, on the same learned model. ``--work DIR`` keeps the
campaigns' journals there (``DIR/written/journal.sqlite``, ``DIR/learned/...``).

1. *Learn*: the virtual robot (``dxboard emulate models/tedusar --robot``, every unprotected
   channel on, every node of ``processes:`` started as a plain process on ROS 2, on a domain of
   its own) is watched by ``dxboard model learn --board --probe`` for ``--duration`` s; the
   learn time is the command's wall time. The learned ``system.yaml`` is used with no edit of
   its model (components, topics, dependencies, rates, tolerances, channels, bands); only the
   deployment differs, because the campaign's daemon starts the nodes itself on Zenoh: the
   written model's ``processes:`` section is appended, ``source: {kind: ros2}`` and
   ``external:`` are left out, each node's ``graph: true`` becomes ``supervised: true`` and
   the nodes read their behaviour from the written model, as the virtual robot's nodes
   always do (``DXBOARD_ROBOT``; ``deploy``). ``dxboard model diff`` of written against
   learned is printed.
2. *Campaign*: ``benchmarks/campaign.py``'s ``Campaign`` runs the same seeded fault set (its
   ``plan_trials``) and a fault-free run of ``--quiet-s`` seconds on each model in turn. A
   trial's *first diagnosis* is the basis of its first repair plan (``Trial.first_plan_basis``);
   the share of trials whose first diagnoses are identical under both models is the figure
   (goal >= 95 %), with false repairs (actions on components the fault does not allow) and
   repair actions in fault-free time (goal 0).
"""

from __future__ import annotations

import argparse
import asyncio
import json
import os
import random
import re
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from benchmarks._rigs.robots import KEY  # noqa: E402
from benchmarks.campaign import Campaign  # noqa: E402
from benchmarks.campaign_plan import Trial, plan_trials  # noqa: E402
from host.experiment.robot import fast_model  # noqa: E402
from host.launch.boards import RunningBoard  # noqa: E402
from host.launch.domains import claim_domain, domain_env  # noqa: E402
from host.launch.waiting import wait_until  # noqa: E402

TEDUSAR = ROOT / "models" / "tedusar"
DXBOARD = str(Path(sys.executable).parent / "dxboard")
PROTECTED = 2


def node_names(system: str) -> list[str]:
    section = system.split("\nprocesses:\n", 1)[1]
    return re.findall(r"^  (\w+): \{command", section, re.M)


def learn(out: Path, duration: float, env: dict[str, str]) -> float:
    """Start the virtual robot on ROS 2, learn it with the probe; the learn's wall time."""
    work = Path(tempfile.mkdtemp(prefix="dxboard-learn-robot-"))
    robot_dir = fast_model(TEDUSAR, work)
    robot = RunningBoard(robot_dir, key=KEY)
    procs: list[subprocess.Popen[bytes]] = []
    try:
        for ch in range(10):
            if ch != PROTECTED:
                robot.board("on", str(ch))
        node_env = {**env, "DXBOARD_MIDDLEWARE": "ros2", "PYTHONPATH": str(ROOT),
                    "DXBOARD_DEVICES": json.dumps(robot.devices)}
        names = node_names((TEDUSAR / "system.yaml").read_text())
        for name in names:
            argv = [sys.executable, "-m", "emulator.robot.node", name, str(robot_dir)]
            if name == "hokuyo_node":
                argv.append("--managed")  # as the written model starts it on ROS 2
            procs.append(subprocess.Popen(argv, env=node_env, cwd=ROOT,
                                          stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL))
        wait_until(lambda: _graph_has(names, env), 120, "every node in the ROS 2 graph")
        board = robot.urls["board"].removeprefix("tcp://")
        t0 = time.monotonic()
        p = subprocess.run([DXBOARD, "model", "learn", str(out), "--duration", str(duration),
                            "--board", board, "--probe"], env={**env, "DXBOARD_KEY": KEY.hex()},
                           cwd=ROOT, capture_output=True, text=True, timeout=duration + 600)
        took = time.monotonic() - t0
        sys.stderr.write(p.stderr)
        if p.returncode != 0:
            raise RuntimeError(f"dxboard model learn failed: {p.stdout} {p.stderr}")
        print(p.stdout.strip())
        return took
    finally:
        for q in procs:
            q.terminate()
        for q in procs:
            try:
                q.wait(20)
            except subprocess.TimeoutExpired:
                q.kill()
                q.wait(20)
        robot.stop()
        shutil.rmtree(work, ignore_errors=True)


def _graph_has(names: list[str], env: dict[str, str]) -> bool:
    """Every node (rviz aside) in the graph, and /scan and /odom publishing."""
    p = subprocess.run([sys.executable, "-c", GRAPH_CHECK], env=env, capture_output=True,
                       text=True, timeout=300)
    seen = p.stdout.split()
    return set(names) - {"rviz"} <= set(seen) and {"/scan", "/odom"} <= set(seen)


GRAPH_CHECK = """
import rclpy, time
from rclpy.node import Node
from rclpy.qos import qos_profile_sensor_data
from nav_msgs.msg import Odometry
from sensor_msgs.msg import LaserScan
rclpy.init()
n = Node("bench_graph_check")
got = set()
for topic, kind in (("/scan", LaserScan), ("/odom", Odometry)):
    n.create_subscription(kind, topic, lambda m, t=topic: got.add(t), qos_profile_sensor_data,
                          raw=True)
end = time.monotonic() + 5
while time.monotonic() < end:
    rclpy.spin_once(n, timeout_sec=0.1)
print(" ".join([x for x, _ in n.get_node_names_and_namespaces()] + sorted(got)))
"""


def deploy(learned: Path, dest: Path) -> Path:
    """The learned model made to run as the campaign runs it (see the module): a copy of the
    TEDUSAR directory (emulator, devices, repair domain) with the learned ``system.yaml``."""
    d = dest / "tedusar"
    shutil.copytree(TEDUSAR, d)
    written = (TEDUSAR / "system.yaml").read_text()
    started = set(node_names(written))
    text = learned.read_text().split("\n# Started elsewhere", 1)[0]
    text = text.replace("  source: {kind: ros2}\n", "")
    lines = []
    for line in text.splitlines():
        m = re.match(r"^    (\w+): \{graph: true\}$", line)
        if m and m.group(1) not in started:
            continue
        lines.append(line.replace("{graph: true}", "{supervised: true}"))
    # the nodes are the virtual robot's: they read their behaviour from the written model
    procs = re.sub(r"^(  \w+: \{)", rf'\1env: {{DXBOARD_ROBOT: "{TEDUSAR}"}}, ',
                   written.split("\nprocesses:\n", 1)[1], flags=re.M)
    text = "\n".join(lines) + "\n\nprocesses:\n" + procs
    (d / "system.yaml").write_text(text)
    return d


async def campaign(system_dir: Path, args: argparse.Namespace,
                   tmp: Path) -> tuple[list[Trial], dict[str, Any]]:
    plan = plan_trials(random.Random(args.seed), args.singles, args.doubles)
    if args.trials:
        plan = [p for p in plan if p.index in args.trials]
    c = Campaign(fast_model(system_dir, tmp), tmp / "journal.sqlite")
    try:
        await c.open()
        quiet = await c.quiet(args.quiet_s)
        print(f"  fault-free {quiet['seconds']:g} s: {quiet['repairs']} repair actions, "
              f"{quiet['false_alarms']} abnormal diagnoses"
              + (f" {quiet['alarms']}" if quiet["alarms"] else ""), flush=True)
        trials = []
        for p in plan:
            trials.append(await c.trial(p))
            t = trials[-1]
            print(f"  trial {t.index}: {'+'.join(t.kinds)} on {t.targets}: first plan on "
                  f"{t.first_plan_basis}, false repairs {t.false_repairs}", flush=True)
        return trials, quiet
    finally:
        await c.close()


def _indices(text: str) -> set[int]:
    try:
        return {int(x) for x in text.split(",") if x.strip()}
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r}: give trial indices, e.g. 3,7") from None


def main() -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--duration", type=float, default=60.0)
    p.add_argument("--singles", type=int, default=6)
    p.add_argument("--doubles", type=int, default=2)
    p.add_argument("--quiet-s", type=float, default=60.0)
    p.add_argument("--seed", type=int, default=1)
    p.add_argument("--keep", metavar="DIR", help="keep the learned model here")
    p.add_argument("--learned", metavar="DIR", help="use the model a run kept here (no learn)")
    p.add_argument("--trials", type=_indices, default=None, metavar="I,J",
                   help="only these trials of the plan (indices)")
    p.add_argument("--models", default="written,learned", help="written, learned or both")
    p.add_argument("--work", metavar="DIR", help="keep the campaigns' files (journals) in this "
                   "new directory")
    args = p.parse_args()
    if args.work:
        try:
            Path(args.work).mkdir(parents=True)
        except OSError as e:
            p.error(f"--work {args.work}: {e.strerror}; give a new directory")
    if args.keep and (Path(args.keep) / "system.yaml").exists():
        p.error(f"--keep {args.keep}: it already holds a system.yaml; give a new directory, or "
                f"--learned {args.keep} to use that model")
    if args.learned and not (Path(args.learned) / "system.yaml").is_file():
        p.error(f"--learned {args.learned}: no system.yaml there; keep one with --keep DIR")
    models = [m for m in args.models.split(",") if m]
    if not models or set(models) - {"written", "learned"}:
        p.error(f"--models {args.models}: give written, learned or written,learned")
    with tempfile.TemporaryDirectory(prefix="dxboard-learn-bench-") as tmp_s, \
            claim_domain() as domain:
        tmp = Path(args.work) if args.work else Path(tmp_s)
        env = {**os.environ, **domain_env(domain), "PYTHONPATH": str(ROOT)}
        if args.learned:
            out = Path(args.learned)
            print(f"the model learned before, in {out}")
        else:
            out = Path(args.keep) if args.keep else tmp / "learned"
            took = learn(out, args.duration, env)
            print(f"learn time: {took:.1f} s wall for a {args.duration:g} s watch and the probe")
        diff = subprocess.run([DXBOARD, "model", "diff", str(TEDUSAR), str(out)], env=env,
                              capture_output=True, text=True, timeout=120)
        print(f"model diff written -> learned ({len(diff.stdout.splitlines())} lines):")
        print(diff.stdout + diff.stderr)
        runnable = deploy(out / "system.yaml", tmp / "deployed")
        results = {}
        for name, model in (("written", TEDUSAR), ("learned", runnable)):
            if name not in models:
                continue
            print(f"campaign on the {name} model:", flush=True)
            (tmp / name).mkdir()
            results[name] = asyncio.run(campaign(model, args, tmp / name))
        if len(results) < 2:
            return 0
        (w, wq), (lt, lq) = results["written"], results["learned"]
        same = sum(1 for a, b in zip(w, lt, strict=True)
                   if sorted(a.first_plan_basis) == sorted(b.first_plan_basis))
        print(f"\nidentical first diagnoses: {same} of {len(w)} "
              f"({100 * same / max(1, len(w)):.0f} %)")
        for name, trials, quiet in (("written", w, wq), ("learned", lt, lq)):
            print(f"{name}: false repairs in the trials {sum(t.false_repairs for t in trials)}; "
                  f"fault-free {quiet['seconds']:g} s: {quiet['repairs']} repair actions, "
                  f"{quiet['false_alarms']} abnormal diagnoses")
        print(f"load average {' '.join(f'{x:.2f}' for x in os.getloadavg())}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
