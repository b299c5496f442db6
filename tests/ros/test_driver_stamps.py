"""A driver stamps its messages with the device's time, as urg_node stamps a scan: a burst of frames
it reads late (it was descheduled, the device's process stalled) keeps the device's spacing.

The driver is the real node process (``python -m emulator.robot.node hokuyo_node DIR`` in ROS 2
mode) against a device of the test's own: a TCP server that sends lidar frames every 25 ms of
its clock (``t_ms``), holds some back and then sends them together, each stamped with the time
it was due (as the emulator's devices do after a stall). The stamps are read by a plain rclpy
subscriber that knows no dxboard (``tests.ros.conftest.Peer``).
"""

from __future__ import annotations

import itertools
import json
import socket
import subprocess
import sys
import threading
import time
from pathlib import Path
from typing import Any

from sensor_msgs.msg import LaserScan

from tests.robot.conftest import ROOT
from tests.ros.conftest import Peer
from tests.wait import wait_until

PERIOD_MS = 25
HELD = 12  # frames held back by the device and then sent together


def frame(k: int) -> bytes:
    """Lidar frame ``k``: its number rides in the first range (1000 + k mm)."""
    return json.dumps({"seq": k, "t_ms": 5000 + k * PERIOD_MS, "angle_min": -2.0,
                       "angle_increment": 0.01, "range_max_mm": 30000,
                       "ranges_mm": [1000 + k, 2000]}).encode() + b"\n"


class Device:
    """Sends frames every 25 ms once a client connects: steady until ``go`` is set, then 20
    more, then ``HELD`` frames all at once when the last of them is due (``held``: their
    numbers), then 20 more."""

    def __init__(self) -> None:
        self.server = socket.create_server(("127.0.0.1", 0))
        self.port = self.server.getsockname()[1]
        self.go = threading.Event()
        self.done = threading.Event()
        self.held: list[int] = []
        self.last = -1
        self.thread = threading.Thread(target=self._serve, daemon=True)
        self.thread.start()

    def _serve(self) -> None:
        conn, _ = self.server.accept()
        with conn:
            start, k, end = time.monotonic(), 0, None
            while (end is None or k <= end) and not self.done.is_set():
                if end is None and self.go.is_set():
                    self.held = list(range(k + 20, k + 20 + HELD))
                    end = self.last = self.held[-1] + 20
                if k in self.held:
                    k = self.held[-1]
                    time.sleep(max(0.0, start + k * PERIOD_MS / 1000 - time.monotonic()))
                    conn.sendall(b"".join(frame(i) for i in self.held))
                    k += 1
                    continue
                time.sleep(max(0.0, start + k * PERIOD_MS / 1000 - time.monotonic()))
                conn.sendall(frame(k))
                k += 1
            self.done.wait(30)

    def close(self) -> None:
        self.done.set()
        self.server.close()


def test_a_burst_read_late_keeps_the_devices_spacing_and_no_stamp_is_in_the_future(
        robot_dir: Path, env: dict[str, str], peer: Peer, tmp_path: Path) -> None:
    seen: list[tuple[int, int, int]] = []  # (frame, stamp ns, arrival ns on the same clock)
    lock = threading.Lock()

    def on(msg: Any) -> None:
        arrived = time.time_ns()  # the ROS clock of a node is the system clock
        with lock:
            seen.append((round(msg.ranges[0] * 1000) - 1000,
                         msg.header.stamp.sec * 1_000_000_000 + msg.header.stamp.nanosec,
                         arrived))

    peer.node.create_subscription(LaserScan, "/scan", on, 200)
    device = Device()
    log = (tmp_path / "hokuyo_node.log").open("w")
    proc = subprocess.Popen(
        [sys.executable, "-m", "emulator.robot.node", "hokuyo_node", str(robot_dir)],
        stdout=subprocess.DEVNULL, stderr=log, cwd=ROOT,
        env={**env, "DXBOARD_MIDDLEWARE": "ros2", "PYTHONPATH": str(ROOT),
             "DXBOARD_DEVICES": json.dumps({"hokuyo": f"tcp://127.0.0.1:{device.port}"})})
    try:
        def count() -> int:
            with lock:
                return len(seen)
        wait_until(lambda: count() >= 5, 60, "the peer receiving /scan")
        device.go.set()
        wait_until(lambda: device.last >= 0 and any(k >= device.last for k, _, _ in list(seen)),
                   60, "the last frame at the peer", show=lambda: f"{count()} scans")
    finally:
        device.close()
        proc.terminate()
        proc.wait(20)
        log.close()
    with lock:
        got = {k: (stamp, arrived) for k, stamp, arrived in seen}
    burst = [device.held[0] - 1, *device.held]
    assert all(k in got for k in burst), sorted(got)
    stamps = [got[k][0] for k in burst]
    gaps_ms = [(b - a) / 1e6 for a, b in itertools.pairwise(stamps)]
    # the device's spacing, not the instant they were published (all within a millisecond)
    assert all(abs(g - PERIOD_MS) < 0.01 for g in gaps_ms), gaps_ms
    # never in the future of the clock they are mapped onto
    assert all(stamp <= arrived for stamp, arrived in got.values()), [
        (k, (s - a) / 1e6) for k, (s, a) in sorted(got.items()) if s > a]
    # and near when the frames were taken: the offset is the least delay seen
    assert all(got[k][1] - got[k][0] < 5e9 for k in got)
