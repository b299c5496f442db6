"""The devices of ``dxboard emulate --robot`` over TCP: power, boot, hang, data and commands."""

from __future__ import annotations

import json
import socket
import subprocess
import time
from pathlib import Path
from typing import Any

import pytest

from tests.robot.conftest import DXBOARD, ROOT, Robot


class Conn:
    """A client of one device: lines in, lines out."""

    def __init__(self, port: int) -> None:
        self.sock = socket.create_connection(("127.0.0.1", port), timeout=2)
        self.buf = b""
        self.closed = False

    def read(self, seconds: float) -> list[dict[str, Any]]:
        """Every frame received during ``seconds``."""
        end = time.monotonic() + seconds
        while time.monotonic() < end and not self.closed:
            self.sock.settimeout(max(0.01, end - time.monotonic()))
            try:
                data = self.sock.recv(65536)
            except TimeoutError:
                continue
            except ConnectionError:
                data = b""
            if not data:
                self.closed = True
            self.buf += data
        *lines, self.buf = self.buf.split(b"\n")
        return [json.loads(line) for line in lines]

    def send(self, obj: object) -> None:
        self.sock.sendall(json.dumps(obj).encode() + b"\n")

    def close(self) -> None:
        self.sock.close()


def test_prints_a_url_per_device(robot: Robot) -> None:
    assert set(robot.devices) == {"jaguar", "hokuyo", "laser_alignment", "imu", "joystick",
                                  "thermal_camera"}
    assert all(u.startswith("tcp://127.0.0.1:") and not u.endswith(":0")
               for u in robot.devices.values())
    assert robot.stop() == 0  # SIGTERM: a clean exit


def test_unpowered_device_refuses_booting_sends_nothing_then_scans(robot: Robot) -> None:
    with pytest.raises(ConnectionRefusedError):
        Conn(robot.port("hokuyo"))
    robot.board("on", "hokuyo")
    booting = Conn(robot.port("hokuyo"))  # boot_ms 1500 in these tests: still booting
    assert booting.read(0.5) == []
    assert not booting.closed
    first = booting.read(3.0)  # booted: frames on the same connection
    assert first, "no scan after boot"
    frames = booting.read(2.0)
    assert 60 <= len(frames) <= 100, len(frames)  # 40 Hz over 2 s, generous
    scan = frames[-1]
    assert len(scan["ranges_mm"]) == 1081 and scan["angle_increment"] > 0
    assert all(100 <= r <= 30000 for r in scan["ranges_mm"])
    assert [f["seq"] for f in frames] == list(range(frames[0]["seq"], frames[-1]["seq"] + 1))
    booting.close()


def test_always_powered_devices_serve_at_their_rates(robot: Robot) -> None:
    imu = Conn(robot.port("imu"))
    imu.read(0.3)
    n_imu = len(imu.read(2.0))
    joy = Conn(robot.port("joystick"))
    joy.read(0.3)
    n_joy = len(joy.read(2.0))
    assert 150 <= n_imu <= 250, n_imu  # 100 Hz
    assert 12 <= n_joy <= 28, n_joy  # 10 Hz


def test_hang_keeps_connection_and_current_power_off_drops_it(robot: Robot) -> None:
    robot.board("on", "hokuyo")
    time.sleep(2.0)
    conn = Conn(robot.port("hokuyo"))
    assert conn.read(0.5), "no scans from a booted hokuyo"
    robot.inject("hokuyo", "hang")
    conn.read(0.2)  # what was on the way
    assert conn.read(1.0) == []
    assert not conn.closed
    ch = robot.channel("hokuyo")
    assert 200 <= ch["current_ma"] <= 1200, ch  # system.yaml's band: a hang looks healthy
    robot.board("off", "hokuyo")
    conn.read(1.0)
    assert conn.closed, "powering off did not drop the connection"
    with pytest.raises(ConnectionRefusedError):
        Conn(robot.port("hokuyo"))
    robot.board("on", "hokuyo")  # a power cycle cures a non-permanent hang
    time.sleep(2.0)
    assert Conn(robot.port("hokuyo")).read(0.5)


def test_base_follows_velocity_commands_and_rejects_bad_ones(robot: Robot) -> None:
    robot.board("on", "jaguar")
    time.sleep(0.8)
    base = Conn(robot.port("jaguar"))
    base.send({"cmd": "fly"})
    base.send({"cmd": "velocity", "linear": "fast", "angular": 0})
    lines = base.read(0.5)
    errors = [f["error"] for f in lines if "error" in f]
    assert len(errors) == 2 and "velocity" in errors[0] and "linear" in errors[1], errors
    assert all(abs(f["yaw_rate"]) < 0.05 for f in lines if "yaw_rate" in f)
    for _ in range(10):  # hold the command (the base stops 0.5 s after the last one)
        base.send({"cmd": "velocity", "linear": 0.3, "angular": 0.8})
        frames = base.read(0.1)
    assert 0.7 <= frames[-1]["yaw_rate"] <= 0.9, frames[-1]
    assert frames[-1]["speed"] > 0.2
    time.sleep(1.0)  # no more commands: it stops
    assert abs(base.read(0.3)[-1]["yaw_rate"]) < 0.05


def test_bad_robot_file_is_one_line_exit_2(robot_dir: Path) -> None:
    (robot_dir / "robot.yaml").write_text("devices:\n  hokuyo: {kind: lidar, channel: nope, "
                                          "rate_hz: 40}\n")
    p = subprocess.run([DXBOARD, "emulate", str(robot_dir), "--robot"], capture_output=True,
                       text=True, timeout=30, cwd=ROOT)
    assert p.returncode == 2, p.stderr
    assert p.stdout == ""
    assert len(p.stderr.strip().splitlines()) == 1, p.stderr
    assert "robot.yaml" in p.stderr and "hokuyo" in p.stderr and "nope" in p.stderr
