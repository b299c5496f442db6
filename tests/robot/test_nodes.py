"""The robot's nodes as real processes on real zenoh, driven by the emulated board's faults."""

from __future__ import annotations

import os
import subprocess
import sys
import time
from pathlib import Path

from tests.rates import assert_rate
from tests.robot.conftest import ROOT, Nodes, Robot, Topics, serving
from tests.wait import wait_until


def test_hokuyo_node_publishes_scan_at_40_hz_and_a_hang_stops_it(
        robot: Robot, topics: Topics, nodes: Nodes) -> None:
    nodes.start("hokuyo_node")  # before the device is powered: it waits
    topics.wait_peers(1)  # the node is up, on the bus
    assert nodes.running("hokuyo_node")
    assert topics.messages("/scan") == []
    robot.board("on", "hokuyo")
    scans = topics.collect("/scan", 80)  # 2 s at 40 Hz
    assert_rate([m["t_ms"] for m in scans], 40, "/scan")
    assert len(scans[-1]["ranges_mm"]) == 1081
    robot.inject("hokuyo", "hang")
    topics.wait_silent("/scan", 1.5)  # what was on the way arrives; then nothing
    ch = robot.channel("hokuyo")
    assert 200 <= ch["current_ma"] <= 1200, ch  # in system.yaml's band: it looks healthy
    assert ch["state"] == "on"
    assert nodes.running("hokuyo_node")


def test_driver_stays_silent_after_power_off_until_restarted(
        robot: Robot, topics: Topics, nodes: Nodes) -> None:
    robot.board("on", "jaguar")
    nodes.start("jaguar_node")
    odom = topics.collect("/odom", 40)  # 2 s at 20 Hz
    assert_rate([m["t_ms"] for m in odom], 20, "/odom")
    robot.board("off", "jaguar")
    topics.wait_silent("/odom", 1.0)
    robot.board("on", "jaguar")  # the device is back (boot 0.3 s) but its driver lost it
    serving(robot, "jaguar").close()  # the device sends again ...
    assert topics.count_over("/odom", 1.5) == 0  # ... and its driver does not
    assert nodes.running("jaguar_node")
    assert "lost the connection to jaguar" in nodes.log("jaguar_node")
    assert nodes.stop("jaguar_node") == 0  # a clean exit on SIGTERM
    nodes.start("jaguar_node")  # the repair: restart the driver
    topics.wait_for("/odom")


def test_hector_mapping_publishes_map_only_while_scans_arrive(
        robot: Robot, topics: Topics, nodes: Nodes) -> None:
    nodes.start("hokuyo_node", "hector_mapping")
    topics.wait_peers(2)  # both nodes are up
    assert topics.count_over("/map", 2.5) == 0  # no scans yet: no map (it would every 2 s)
    robot.board("on", "hokuyo")
    topics.wait_for("/scan")
    topics.wait_for("/map")
    t0 = time.monotonic()
    topics.collect("/map", 3)  # every 2 s
    maps = topics.arrivals("/map", t0)
    assert_rate([1000 * t for t in maps], 0.5, "/map")
    poses, scans = topics.messages("/slam_out_pose", t0), topics.messages("/scan", t0)
    assert len(poses) >= 0.8 * len(scans) > 100, (len(poses), len(scans))  # one per scan
    robot.board("off", "hokuyo")
    topics.wait_silent("/scan", 1.0)
    topics.wait_silent("/slam_out_pose", 0.5)
    topics.wait_silent("/map", 4.5)  # at most a last map; then none for two periods
    assert nodes.running("hector_mapping")


def test_teleop_drives_the_base_and_imu_sees_the_same_turn(
        robot: Robot, topics: Topics, nodes: Nodes) -> None:
    robot.board("on", "jaguar")
    nodes.start("joy_node", "jaguar_teleop_node", "jaguar_node", "imu_node")
    topics.wait_for("/odom")
    topics.wait_for("/cmd_vel")
    t0 = time.monotonic()
    wait_until(lambda: len(topics.messages("/cmd_vel", t0)) >= 30
               and len(topics.messages("/odom", t0)) >= 60
               and len(topics.messages("/imu_data", t0)) >= 300, what="3 s of driving")
    assert_rate([1000 * t for t in topics.arrivals("/cmd_vel", t0)], 10, "/cmd_vel")
    odom = topics.messages("/odom", t0)
    imu = topics.messages("/imu_data", t0)
    # the joystick turns 0.6 rad/s at most, every 6 s: the base turns, odom and IMU agree
    assert max(abs(o["yaw_rate"]) for o in odom) > 0.2
    imu_at = {round(m["t_ms"] / 10): m["yaw_rate"] for m in imu}
    diffs = [abs(o["yaw_rate"] - imu_at[round(o["t_ms"] / 10)]) for o in odom
             if round(o["t_ms"] / 10) in imu_at]
    assert len(diffs) > 10
    assert sum(diffs) / len(diffs) < 0.05, diffs


def test_laser_alignment_control_levels_the_mount(
        robot: Robot, topics: Topics, nodes: Nodes) -> None:
    robot.board("on", "laser_alignment")
    nodes.start("imu_node", "laser_alignment_control", "laser_alignment_node")
    topics.wait_for("/laser_alignment/state")

    def level() -> bool:
        states = topics.messages("/laser_alignment/state")
        commands = topics.messages("/laser_alignment/command")
        return bool(states and commands) and abs(
            states[-1]["target_roll"] - commands[-1]["roll"]) < 0.05

    wait_until(level, what="the mount's target to follow the controller's command",
               show=lambda: (topics.messages("/laser_alignment/state")[-1:],
                             topics.messages("/laser_alignment/command")[-1:]))
    nodes.stop("imu_node")  # its input stops: so does the controller's output
    topics.wait_silent("/laser_alignment/command", 1.0)
    assert topics.count_over("/laser_alignment/command", 1.0) == 0
    assert nodes.running("laser_alignment_control")


def test_bad_name_or_environment_is_one_line_exit_2(robot_dir: Path) -> None:
    env = {k: v for k, v in os.environ.items() if k != "DXBOARD_DEVICES"}
    for name in ("no_such_node", "hokuyo"):  # hokuyo is hardware, not a node
        p = subprocess.run([sys.executable, "-m", "emulator.robot.node", name, str(robot_dir)],
                           capture_output=True, text=True, timeout=30, cwd=ROOT, env=env)
        assert p.returncode == 2 and "no node" in p.stderr, p.stderr
        assert len(p.stderr.strip().splitlines()) == 1, p.stderr
    p = subprocess.run([sys.executable, "-m", "emulator.robot.node", "hokuyo_node",
                        str(robot_dir)], capture_output=True, text=True, timeout=30, cwd=ROOT,
                       env=env)
    assert p.returncode == 2 and "DXBOARD_DEVICES" in p.stderr.splitlines()[-1], p.stderr


def test_exit_without_device_exits_1_when_its_device_is_off_or_lost(
        robot: Robot, topics: Topics, nodes: Nodes) -> None:
    """``--exit-without-device``: a driver as usb_cam is, for the daemon's crash-loop test."""
    nodes.start("jaguar_node", extra=("--exit-without-device",))  # the base is off
    wait_until(lambda: not nodes.running("jaguar_node"), 60, "the driver's exit")
    assert nodes.stop("jaguar_node") == 1
    assert "jaguar at 127.0.0.1" in nodes.log("jaguar_node")
    robot.board("on", "jaguar")
    nodes.start("jaguar_node", extra=("--exit-without-device=60",))
    topics.wait_for("/odom")
    robot.board("off", "jaguar")  # the base loses its power: the driver its connection
    wait_until(lambda: not nodes.running("jaguar_node"), 60, "the driver's exit")
    assert nodes.stop("jaguar_node") == 1
    assert "lost the connection to jaguar" in nodes.log("jaguar_node")
    p = subprocess.run([sys.executable, "-m", "emulator.robot.node", "jaguar_node",
                        "--exit-without-device=soon"], capture_output=True, text=True,
                       timeout=60, cwd=ROOT)
    assert p.returncode == 2 and "--exit-without-device=soon" in p.stderr, p.stderr
