"""The devices of ``dxboard emulate --robot`` over TCP: power, boot, hang, data and commands."""

from __future__ import annotations

import socket
import subprocess
from pathlib import Path
from typing import Any

import pytest

from tests.rates import assert_no_gaps, assert_rate
from tests.robot.conftest import DXBOARD, ROOT, Conn, Robot, serving
from tests.wait import wait_until


def test_prints_a_url_per_device(robot: Robot) -> None:
    assert set(robot.devices) == {"jaguar", "hokuyo", "laser_alignment", "imu", "joystick",
                                  "thermal_camera"}
    assert all(u.startswith("tcp://127.0.0.1:") and not u.endswith(":0")
               for u in robot.devices.values())
    assert robot.stop() == 0  # SIGTERM: a clean exit


def test_unpowered_device_refuses_booting_sends_nothing_then_scans(robot: Robot) -> None:
    with pytest.raises(ConnectionRefusedError):
        Conn(robot.port("hokuyo"))
    before_ms = robot.now_ms()  # the emulator's clock, before the channel goes on
    robot.board("on", "hokuyo")
    booting = Conn(robot.port("hokuyo"))  # boot_ms 1500 in these tests: still booting
    first = booting.frames(1)  # booted: frames on the same connection
    assert not booting.closed
    assert first[0]["seq"] == 0 and first[0]["t_ms"] >= before_ms + 1500, first[0]["t_ms"]
    frames = booting.frames(80)  # 2 s at 40 Hz
    assert_rate([f["t_ms"] for f in frames], 40, "hokuyo")
    assert_no_gaps([f["seq"] for f in first + frames], "hokuyo")
    scan = frames[-1]
    assert len(scan["ranges_mm"]) == 1081 and scan["angle_increment"] > 0
    assert all(100 <= r <= 30000 for r in scan["ranges_mm"])
    booting.close()


def test_always_powered_devices_serve_at_their_rates(robot: Robot) -> None:
    imu = Conn(robot.port("imu")).frames(200)
    joy = Conn(robot.port("joystick")).frames(20)
    assert_rate([f["t_ms"] for f in imu], 100, "imu")
    assert_rate([f["t_ms"] for f in joy], 10, "joystick")
    assert_no_gaps([f["seq"] for f in imu], "imu")
    assert_no_gaps([f["seq"] for f in joy], "joystick")


def test_hang_keeps_connection_and_current_power_off_drops_it(robot: Robot) -> None:
    robot.board("on", "hokuyo")
    conn = serving(robot, "hokuyo")
    robot.inject("hokuyo", "hang")
    conn.wait_quiet(1.0)  # what was on the way arrives; then nothing
    assert not conn.closed
    ch = robot.channel("hokuyo")
    assert 200 <= ch["current_ma"] <= 1200, ch  # system.yaml's band: a hang looks healthy
    robot.board("off", "hokuyo")
    conn.wait_closed()  # powering off drops the connection
    with pytest.raises(ConnectionRefusedError):
        Conn(robot.port("hokuyo"))
    robot.board("on", "hokuyo")  # a power cycle cures a non-permanent hang
    serving(robot, "hokuyo")


def test_an_unpowered_device_keeps_its_port(robot: Robot) -> None:
    """Refused while off, but nobody else on the machine is given the port meanwhile (a
    second test suite, a browser): the device comes back on the URL it printed."""
    robot.board("on", "jaguar")
    serving(robot, "jaguar").close()  # the client closes first: no TIME_WAIT on the port
    robot.board("off", "jaguar")

    def refused() -> bool:
        try:
            Conn(robot.port("jaguar")).close()
        except ConnectionRefusedError:
            return True
        return False

    wait_until(refused, what="jaguar refusing connections")
    with socket.socket() as other, pytest.raises(OSError, match="in use"):
        other.bind(("127.0.0.1", robot.port("jaguar")))
    assert_not_taken_by_a_reusing_listener(robot.port("jaguar"))
    robot.board("on", "jaguar")
    serving(robot, "jaguar").close()  # back on the URL it printed


def test_a_device_never_powered_yet_keeps_its_port_from_a_reusing_listener(robot: Robot
                                                                           ) -> None:
    """The ports are taken at start, devices still off: a server that binds with SO_REUSEADDR
    (zenoh's, asyncio's) on one of them meanwhile is refused, so the device listens on it
    once powered (a zenoh endpoint on the off jaguar's port once made jaguar_node connect to
    zenoh, and the robot never came up)."""
    assert_not_taken_by_a_reusing_listener(robot.port("hokuyo"))
    robot.board("on", "hokuyo")
    serving(robot, "hokuyo").close()


def assert_not_taken_by_a_reusing_listener(port: int) -> None:
    with socket.socket() as other:
        other.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
        with pytest.raises(OSError, match="in use"):
            other.bind(("127.0.0.1", port))
            other.listen()


def test_base_follows_velocity_commands_and_rejects_bad_ones(robot: Robot) -> None:
    robot.board("on", "jaguar")
    base = serving(robot, "jaguar")
    base.send({"cmd": "fly"})
    base.send({"cmd": "velocity", "linear": "fast", "angular": 0})
    lines: list[dict[str, Any]] = []
    wait_until(lambda: len([f for f in lines if "error" in f]) >= 2 or lines.extend(
        base.read(0.2)), what="two error replies", show=lambda: lines[-3:])
    errors = [f["error"] for f in lines if "error" in f]
    assert len(errors) == 2 and "velocity" in errors[0] and "linear" in errors[1], errors
    assert all(abs(f["yaw_rate"]) < 0.05 for f in lines if "yaw_rate" in f)
    sent: list[float] = []

    def turning() -> dict[str, Any] | None:
        # hold the command (the base stops 0.5 s after the last one) until it turns
        base.send({"cmd": "velocity", "linear": 0.3, "angular": 0.8})
        frames = base.read(0.1)
        sent.append(1)
        return next((f for f in reversed(frames) if 0.7 <= f["yaw_rate"] <= 0.9), None)

    frame = wait_until(turning, what="the base turning at 0.8 rad/s")
    assert frame["speed"] > 0.2
    last_ms = frame["t_ms"]
    # no more commands: it stops (0.5 s after the last command, by the emulator's clock)
    stopped = wait_until(lambda: next((f for f in base.read(0.2) if abs(f["yaw_rate"]) < 0.05),
                                      None), what="the base to stop")
    assert stopped["t_ms"] - last_ms >= 300, (last_ms, stopped)  # held, then stopped


def test_bad_robot_file_is_one_line_exit_2(robot_dir: Path) -> None:
    (robot_dir / "robot.yaml").write_text("devices:\n  hokuyo: {kind: lidar, channel: nope, "
                                          "rate_hz: 40}\n")
    p = subprocess.run([DXBOARD, "emulate", str(robot_dir), "--robot"], capture_output=True,
                       text=True, timeout=30, cwd=ROOT)
    assert p.returncode == 2, p.stderr
    assert p.stdout == ""
    assert len(p.stderr.strip().splitlines()) == 1, p.stderr
    assert "robot.yaml" in p.stderr and "hokuyo" in p.stderr and "nope" in p.stderr
