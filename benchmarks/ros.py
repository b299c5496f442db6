"""ROS 2 benchmark: the daemon's cost of observing the TEDUSAR topics over ROS 2 against Zenoh.

Run with the project's Python (``.venv/bin/python benchmarks/ros.py [--seconds 20]``). One
``dxboard emulate --robot`` serves the virtual robot's devices (Hokuyo and Jaguar switched
on); for each middleware in turn the same driver processes run (``hokuyo_node`` /scan
LaserScan 40 Hz, ``imu_node`` /imu_data Imu 100 Hz, ``jaguar_node`` /odom 20 Hz,
``joy_node`` /joy 10 Hz) and an observer process opens the daemon's source for it
(``ZenohSource`` or ``Ros2Source``) with the model's frequency observers in an
``ObserverHub``, as the daemon does. After a warm-up it measures the observer process's CPU
time (``time.process_time``: all its threads, DDS or Zenoh included) over ``--seconds`` wall
seconds and the messages it received; then, ``--cycles`` times, the IMU driver is stopped
and the time from the last ``/imu_data`` message to ``¬ok(/imu_data)`` is taken (the silence
rule is 5 periods, 50 ms at 100 Hz; the rest is scheduling). Figures go to RESULTS.md by hand;
the CPU ratio ros2/zenoh is the result, the absolute numbers depend on the machine and its load.

Replay speed (``--replay``, or ``--replay-only``): the same drivers on ROS 2 are recorded by
``dxboard record`` for ``--seconds``; then, in this process, the bag is read three times: only
reading its messages (rosbags, the baseline), and ``dxboard replay``'s work (the model's
topic observers and the diagnoser on the bag's clock, journaled) — bag seconds per wall
second for each, and the ratio of the two.
"""

from __future__ import annotations

import argparse
import asyncio
import json
import os
import shutil
import signal
import socket
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # the checkout before benchmarks/

ROOT = Path(__file__).resolve().parents[1]
KEY_HEX = "000102030405060708090a0b0c0d0e0f"
DRIVERS = ("hokuyo_node", "imu_node", "jaguar_node", "joy_node")
TOPICS = {"/scan": (40, 10, 0.5), "/imu_data": (100, 25, 0.5), "/odom": (20, 5, 1.0),
          "/joy": (10, 4, 1.0)}


# -- the observer process ------------------------------------------------------------------
async def observe(middleware: str, endpoint: str, seconds: float, cycles: int) -> None:
    from host.observers.base import Update
    from host.observers.hub import ObserverHub
    from host.observers.sources.base import TopicSource
    from host.observers.topics import FrequencyObserver

    source: TopicSource
    if middleware == "ros2":
        from host.observers.sources.ros2 import Ros2Source
        source = Ros2Source()
    else:
        from host.observers.sources.zenoh_peer import ZenohSource
        source = ZenohSource(listen=(endpoint,))
    count = [0]
    last_imu = [0.0]
    state: dict[str, bool | None] = {}
    silent_at: list[float] = []

    def sink(updates: list[Update]) -> None:
        from host.diagnosis.observations import Observation
        for u in updates:
            if isinstance(u, Observation):
                if u.literal.atom == "ok(/imu_data)" and state.get(u.literal.atom) is not False \
                        and not u.literal.positive:
                    silent_at.append(time.monotonic() - last_imu[0])
                state[u.literal.atom] = u.literal.positive

    observers = [FrequencyObserver(t, r, tol, w) for t, (r, tol, w) in TOPICS.items()]
    hub = ObserverHub(observers, sink)
    feed = hub.feed_message

    def counting(msg: Any) -> None:
        count[0] += 1
        if msg.topic == "/imu_data":
            last_imu[0] = time.monotonic()
        feed(msg)

    hub.feed_message = counting  # type: ignore[method-assign]
    await hub.start(source)
    print("started", flush=True)
    while not all(state.get(f"ok({t})") for t in TOPICS):  # every topic at its rate
        await asyncio.sleep(0.2)
    await asyncio.sleep(2.0)  # warm-up
    c0, n0, t0 = time.process_time(), count[0], time.monotonic()
    await asyncio.sleep(seconds)
    cpu, n, wall = time.process_time() - c0, count[0] - n0, time.monotonic() - t0
    print(json.dumps({"cpu_s": cpu, "wall_s": wall, "messages": n}), flush=True)
    loop = asyncio.get_running_loop()
    for _ in range(cycles):
        print("stop imu", flush=True)
        k = len(silent_at)
        while len(silent_at) == k:
            await asyncio.sleep(0.01)
        print(json.dumps({"silence_s": silent_at[-1]}), flush=True)
        print("start imu", flush=True)
        while not state.get("ok(/imu_data)"):
            await asyncio.sleep(0.05)
    await loop.run_in_executor(None, sys.stdin.readline)  # until the parent says stop
    await hub.close()
    source.close()


# -- the driver of the run -------------------------------------------------------------------
def free_endpoint() -> str:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return f"tcp/127.0.0.1:{s.getsockname()[1]}"


def start_robot(system_dir: Path) -> tuple[subprocess.Popen[str], dict[str, str], str]:
    env = {**os.environ, "DXBOARD_KEY": KEY_HEX}
    proc = subprocess.Popen([sys.executable, "-m", "host.cli", "emulate", str(system_dir),
                             "--robot"], stdout=subprocess.PIPE, stderr=subprocess.DEVNULL,
                            text=True, env=env, cwd=ROOT)
    assert proc.stdout is not None
    devices: dict[str, str] = {}
    board = ""
    while len(devices) < 5:
        line = proc.stdout.readline()
        if not line:
            raise SystemExit("dxboard emulate --robot did not start")
        name, _, url = line.strip().partition(": ")
        if name == "device":
            dev, _, url = url.partition(" ")
            devices[dev] = url
        elif name == "board":
            board = url
    for ch in ("hokuyo", "jaguar"):
        subprocess.run([sys.executable, "-m", "host.cli", "board", board, "on", ch],
                       check=True, env=env, cwd=ROOT, capture_output=True)
    return proc, devices, board


def stop(proc: subprocess.Popen[Any]) -> None:
    if proc.poll() is None:
        proc.send_signal(signal.SIGTERM)
        try:
            proc.wait(15)
        except subprocess.TimeoutExpired:
            proc.kill()
            proc.wait()


def run_one(middleware: str, system_dir: Path, devices: dict[str, str], seconds: float,
            cycles: int) -> dict[str, Any]:
    endpoint = free_endpoint()
    env = {**os.environ, "DXBOARD_MIDDLEWARE": middleware, "DXBOARD_ZENOH": endpoint,
           "DXBOARD_DEVICES": json.dumps(devices), "PYTHONPATH": str(ROOT),
           "ROS_DOMAIN_ID": str(1 + os.getpid() % 100),
           "ROS_AUTOMATIC_DISCOVERY_RANGE": "LOCALHOST"}
    obs = subprocess.Popen([sys.executable, __file__, "--observe", middleware, endpoint,
                            str(seconds), str(cycles)], stdin=subprocess.PIPE,
                           stdout=subprocess.PIPE, text=True, env=env, cwd=ROOT)
    assert obs.stdout is not None and obs.stdin is not None
    assert obs.stdout.readline().strip() == "started"

    def node(name: str) -> subprocess.Popen[str]:
        return subprocess.Popen([sys.executable, "-m", "emulator.robot.node", name,
                                 str(system_dir)], stderr=subprocess.DEVNULL, env=env, cwd=ROOT)

    nodes = {n: node(n) for n in DRIVERS}
    out: dict[str, Any] = json.loads(obs.stdout.readline())
    silences = []
    for _ in range(cycles):
        assert obs.stdout.readline().strip() == "stop imu"
        stop(nodes["imu_node"])
        silences.append(json.loads(obs.stdout.readline())["silence_s"])
        assert obs.stdout.readline().strip() == "start imu"
        nodes["imu_node"] = node("imu_node")
    obs.stdin.write("stop\n")
    obs.stdin.flush()
    obs.wait(30)
    for p in nodes.values():
        stop(p)
    out["silence_s"] = silences
    return out


def replay_speed(system_dir: Path, devices: dict[str, str], seconds: float,
                 tmp: Path) -> dict[str, float]:
    from host.commands.bagrun import load_ros_robot, replay
    from host.journal import Journal
    from host.ros.bag import Bag

    ros_dir = tmp / "tedusar-ros2"
    shutil.copytree(system_dir, ros_dir)
    f = ros_dir / "system.yaml"
    f.write_text(f.read_text().replace("observers:\n", "observers:\n  source: {kind: ros2}\n", 1))
    env = {**os.environ, "DXBOARD_MIDDLEWARE": "ros2", "DXBOARD_DEVICES": json.dumps(devices),
           "PYTHONPATH": str(ROOT), "ROS_DOMAIN_ID": str(1 + (os.getpid() + 50) % 100),
           "ROS_AUTOMATIC_DISCOVERY_RANGE": "LOCALHOST"}
    nodes = [subprocess.Popen([sys.executable, "-m", "emulator.robot.node", n, str(ros_dir)],
                              stderr=subprocess.DEVNULL, env=env, cwd=ROOT) for n in DRIVERS]
    bag_path = tmp / "bench-bag"
    try:
        subprocess.run([sys.executable, "-m", "host.cli", "record", str(ros_dir), str(bag_path),
                        "--duration", str(seconds)], check=True, env=env, cwd=ROOT,
                       capture_output=True)
    finally:
        for p in nodes:
            stop(p)
    robot = load_ros_robot(ros_dir)
    out: dict[str, float] = {}
    for trial in range(3):
        bag = Bag(bag_path)
        t0 = time.perf_counter()
        n = sum(1 for _ in bag.messages())
        read_s = time.perf_counter() - t0
        bag.close()
        bag = Bag(bag_path)
        journal = Journal(tmp / f"replay-{trial}.sqlite", sync="normal")
        stats = replay(robot, bag, journal)
        journal.flush_blocking()
        journal.close()
        bag.close()
        span = bag.end - bag.start
        out = {"messages": n, "bag_s": span, "read_x": max(out.get("read_x", 0.0), span / read_s),
               "replay_x": max(out.get("replay_x", 0.0), span / stats.wall_s),
               "diagnoses": stats.diagnoses}
    out["ratio"] = out["replay_x"] / out["read_x"]
    return out


def main() -> None:
    if len(sys.argv) > 1 and sys.argv[1] == "--observe":
        mw, endpoint, seconds, cycles = sys.argv[2:6]
        asyncio.run(observe(mw, endpoint, float(seconds), int(cycles)))
        return
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--seconds", type=float, default=20.0)
    ap.add_argument("--cycles", type=int, default=10)
    ap.add_argument("--replay", action="store_true", help="also measure the replay speed")
    ap.add_argument("--replay-only", action="store_true", help="only the replay speed")
    args = ap.parse_args()
    from host.experiment.robot import fast_model
    results: dict[str, dict[str, Any]] = {}
    with tempfile.TemporaryDirectory() as tmp:
        system_dir = fast_model(ROOT / "models" / "tedusar", Path(tmp))
        robot, devices, _ = start_robot(system_dir)
        try:
            if not args.replay_only:
                results = {mw: run_one(mw, system_dir, devices, args.seconds, args.cycles)
                           for mw in ("zenoh", "ros2")}
            speed = (replay_speed(system_dir, devices, args.seconds, Path(tmp))
                     if args.replay or args.replay_only else None)
        finally:
            stop(robot)
    if speed is not None:
        print(f"bag: {speed['messages']:.0f} messages, {speed['bag_s']:.1f} s; "
              f"{speed['diagnoses']:.0f} diagnosis changes on replay")
        print(f"reading only: {speed['read_x']:.0f} bag s / wall s; replay (observers, "
              f"diagnoser, journal): {speed['replay_x']:.0f} bag s / wall s; "
              f"replay / reading: {speed['ratio']:.2f}")
    if not results:
        return
    print("| middleware | messages/s | observer CPU (% of a core) | CPU µs/message "
          "| silence → ¬ok p50 | p99 (max) |")
    print("|---|---|---|---|---|---|")
    for mw, r in results.items():
        rate = r["messages"] / r["wall_s"]
        s = sorted(r["silence_s"])
        p99 = s[min(len(s) - 1, int(0.99 * len(s)))]
        print(f"| {mw} | {rate:.0f} | {100 * r['cpu_s'] / r['wall_s']:.1f} | "
              f"{1e6 * r['cpu_s'] / max(1, r['messages']):.0f} | "
              f"{1000 * statistics.median(s):.0f} ms | {1000 * p99:.0f} ms |")
    z, ros = results["zenoh"], results["ros2"]
    print(f"\nCPU per message, ros2 / zenoh: "
          f"{(ros['cpu_s'] / ros['messages']) / (z['cpu_s'] / z['messages']):.2f}")


if __name__ == "__main__":
    main()
