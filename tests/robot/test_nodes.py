"""The robot's nodes as real processes on real zenoh, driven by the emulated board's faults."""

from __future__ import annotations

import os
import subprocess
import sys
import time
from pathlib import Path

from tests.robot.conftest import ROOT, Nodes, Robot, Topics


def test_hokuyo_node_publishes_scan_at_40_hz_and_a_hang_stops_it(
        robot: Robot, topics: Topics, nodes: Nodes) -> None:
    nodes.start("hokuyo_node")  # before the device is powered: it waits
    time.sleep(1.0)
    assert nodes.running("hokuyo_node")
    assert topics.messages("/scan") == []
    robot.board("on", "hokuyo")
    topics.wait_for("/scan", timeout=10)
    n = topics.count_over("/scan", 2.0)
    assert 60 <= n <= 100, n  # 40 Hz
    scan = topics.messages("/scan")[-1]
    assert len(scan["ranges_mm"]) == 1081
    robot.inject("hokuyo", "hang")
    time.sleep(0.3)
    assert topics.count_over("/scan", 1.5) == 0
    ch = robot.channel("hokuyo")
    assert 200 <= ch["current_ma"] <= 1200, ch  # in system.yaml's band: it looks healthy
    assert ch["state"] == "on"
    assert nodes.running("hokuyo_node")


def test_driver_stays_silent_after_power_off_until_restarted(
        robot: Robot, topics: Topics, nodes: Nodes) -> None:
    robot.board("on", "jaguar")
    nodes.start("jaguar_node")
    topics.wait_for("/odom", timeout=10)
    n = topics.count_over("/odom", 2.0)
    assert 30 <= n <= 50, n  # 20 Hz
    robot.board("off", "jaguar")
    time.sleep(0.3)
    assert topics.count_over("/odom", 1.0) == 0
    robot.board("on", "jaguar")  # the device is back (boot 0.3 s) but its driver lost it
    time.sleep(1.0)
    assert topics.count_over("/odom", 1.5) == 0
    assert nodes.running("jaguar_node")
    assert "lost the connection to jaguar" in nodes.log("jaguar_node")
    assert nodes.stop("jaguar_node") == 0  # a clean exit on SIGTERM
    nodes.start("jaguar_node")  # the repair: restart the driver
    topics.wait_for("/odom", timeout=10)


def test_hector_mapping_publishes_map_only_while_scans_arrive(
        robot: Robot, topics: Topics, nodes: Nodes) -> None:
    nodes.start("hokuyo_node", "hector_mapping")
    assert topics.count_over("/map", 3.0) == 0  # no scans yet: no map
    robot.board("on", "hokuyo")
    topics.wait_for("/scan", timeout=10)
    topics.wait_for("/map", timeout=5)
    t0 = time.monotonic()
    assert topics.count_over("/map", 4.5) >= 2  # every 2 s
    assert len(topics.messages("/slam_out_pose", t0)) > 100  # one per scan
    robot.board("off", "hokuyo")
    time.sleep(0.6)
    assert topics.count_over("/map", 4.5) == 0
    assert topics.count_over("/slam_out_pose", 0.5) == 0
    assert nodes.running("hector_mapping")


def test_teleop_drives_the_base_and_imu_sees_the_same_turn(
        robot: Robot, topics: Topics, nodes: Nodes) -> None:
    robot.board("on", "jaguar")
    nodes.start("joy_node", "jaguar_teleop_node", "jaguar_node", "imu_node")
    topics.wait_for("/odom", timeout=10)
    topics.wait_for("/cmd_vel", timeout=10)
    t0 = time.monotonic()
    time.sleep(3.0)
    assert 20 <= len(topics.messages("/cmd_vel", t0)) <= 40  # 10 Hz
    odom = topics.messages("/odom", t0)
    imu = topics.messages("/imu_data", t0)
    assert len(imu) > 200 and len(odom) > 40
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
    topics.wait_for("/laser_alignment/state", timeout=10)
    time.sleep(1.0)
    state = topics.messages("/laser_alignment/state")[-1]
    command = topics.messages("/laser_alignment/command")[-1]
    assert abs(state["target_roll"] - command["roll"]) < 0.05, (state, command)
    nodes.stop("imu_node")  # its input stops: so does the controller's output
    time.sleep(0.8)
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
