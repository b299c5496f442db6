"""The robot's parts without processes: robot.yaml checks, device frames, node behaviours."""

from __future__ import annotations

import math
import random
from pathlib import Path
from typing import Any

import pytest

from emulator import model as emodel
from emulator.robot import behaviours as B
from emulator.robot import devices as D
from emulator.robot.config import DeviceSpec, NodeSpec, RobotModelError, load_node, parse_devices
from tests.robot.conftest import TEDUSAR

EMU = emodel.load(TEDUSAR)


def test_tedusar_robot_file_names_real_channels() -> None:
    from emulator.robot.config import load_devices

    specs = {s.name: s for s in load_devices(TEDUSAR, EMU)}
    assert specs["hokuyo"].channel == 3 and specs["jaguar"].channel == 7
    assert specs["imu"].channel is None and specs["imu"].rate_hz == 100


@pytest.mark.parametrize(("devices", "words"), [
    ({"h": {"kind": "laser", "rate_hz": 40}}, ["'h'", "kind", "lidar"]),
    ({"h": {"kind": "lidar", "rate_hz": 0}}, ["rate_hz"]),
    ({"h": {"kind": "lidar", "rate_hz": 40, "channel": 12}}, ["channel", "12"]),
    ({"h": {"kind": "lidar", "rate_hz": 40, "port": 1}}, ["unknown field", "port"]),
    ({}, ["devices"]),
])
def test_bad_devices_name_the_field(devices: dict[str, Any], words: list[str]) -> None:
    with pytest.raises(RobotModelError) as err:
        parse_devices({"devices": devices}, EMU, "robot.yaml")
    assert all(w in str(err.value) for w in words), err.value
    assert str(err.value).startswith("robot.yaml")


def test_node_spec_from_system_yaml(tmp_path: Path) -> None:
    spec = load_node(TEDUSAR, "hector_mapping")
    assert spec.kind == "N" and spec.subscribes == ("/scan",)
    assert spec.publishes == {"/map": ("/scan",), "/slam_out_pose": ("/scan",)}
    assert load_node(TEDUSAR, "jaguar_node").hardware == ("jaguar",)
    with pytest.raises(RobotModelError, match="no node 'jaguar'"):
        load_node(TEDUSAR, "jaguar")
    with pytest.raises(RobotModelError, match="cannot read"):
        load_node(tmp_path, "rviz")


def test_base_stops_without_power_or_commands() -> None:
    world = D.RobotWorld()
    base = D.Base(DeviceSpec("jaguar", "base", 20, 7), world, random.Random(1))
    base.command({"cmd": "velocity", "linear": 0.5, "angular": 1.0}, 0)
    assert abs(base.frame(1000)["yaw_rate"]) < 0.05  # not working: the motors are off
    base.working(True, 1000)
    for t in range(1000, 1500, 100):
        base.command({"cmd": "velocity", "linear": 0.5, "angular": 1.0}, t)
    assert 0.9 < base.frame(1500)["yaw_rate"] < 1.1
    assert abs(base.frame(3000)["yaw_rate"]) < 0.05  # commands stopped 1.1 s ago
    with pytest.raises(ValueError, match="angular"):
        base.command({"cmd": "velocity", "linear": 0.5}, 3000)


def test_mapping_tracks_the_turn_and_stops_without_scans() -> None:
    world = D.RobotWorld()
    world.drive_ok = True
    lidar = D.Lidar(DeviceSpec("hokuyo", "lidar", 40, 3), world, random.Random(2))
    out: list[tuple[str, dict[str, Any]]] = []
    spec = load_node(TEDUSAR, "hector_mapping")
    m = B.make(spec, lambda t, v: out.append((t, v)))
    for i in range(200):  # 5 s at 40 Hz, turning
        t = 25 * (i + 1)
        world.command(0.0, 0.5 * math.sin(t / 1000), t)
        m.on_message("/scan", lidar.frame(t), t / 1000)
    pose = [v for t, v in out if t == "/slam_out_pose"]
    assert len(pose) == 200
    assert abs(pose[-1]["yaw"] - world.yaw) < 0.05, (pose[-1], world.yaw)
    m.tick(5.1)
    assert out[-1][0] == "/map"
    n = len(out)
    m.tick(5.7)  # the last scan was 0.7 s ago
    assert len(out) == n


def test_relay_publishes_only_while_inputs_arrive() -> None:
    spec = NodeSpec("x", "N", (), {"/out": ("/a", "/b")}, ("/a", "/b"))
    out: list[str] = []
    r = B.make(spec, lambda t, v: out.append(t))
    r.on_message("/a", {}, 0.0)
    r.tick(0.1)
    assert out == []
    r.on_message("/b", {}, 0.1)
    r.tick(0.2)
    assert out == ["/out"]
    r.tick(0.2 + B.STALE_S)
    assert out == ["/out"]
    assert B.device_command("/cmd_vel", {"seq": 3, "linear": 1, "angular": 0}) == {
        "cmd": "velocity", "linear": 1, "angular": 0}
    assert B.device_command("/other", {}) is None
