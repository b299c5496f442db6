"""The conversions between the virtual robot's frames and standard ROS 2 messages, and the
middleware setting of a node (no processes: the conversions are plain functions)."""

from __future__ import annotations

import math
import subprocess
import sys
from pathlib import Path

import pytest
from rclpy.serialization import deserialize_message, serialize_message

from emulator.robot import ros_msgs as R
from emulator.robot.config import load_node
from emulator.robot.driver_status import ERROR, OK, DriverStatus

ROOT = Path(__file__).resolve().parents[2]
STAMP = R.Time(sec=12, nanosec=500)


def roundtrip(topic: str, values: dict[str, object]) -> dict[str, object]:
    kind = R.topic_type(topic)
    wire = serialize_message(kind.to_msg(values, STAMP))  # what DDS carries
    return kind.from_msg(deserialize_message(wire, kind.type))


def test_scan_odom_imu_and_twist_survive_the_wire() -> None:
    scan = roundtrip("/scan", {"angle_min": -2.356194, "angle_increment": 0.004363,
                               "range_max_mm": 30000, "ranges_mm": [1200, 30000, 100]})
    assert scan["ranges_mm"] == [1200, 30000, 100]
    assert scan["range_max_mm"] == 30000
    odom = roundtrip("/odom", {"x": 1.5, "y": -2.0, "yaw": 2.5, "speed": 0.4,
                               "yaw_rate": -0.3})
    assert odom == pytest.approx({"x": 1.5, "y": -2.0, "yaw": 2.5, "speed": 0.4,
                                  "yaw_rate": -0.3})
    imu = roundtrip("/imu_data", {"roll": 0.1, "pitch": -0.2, "yaw": 3.0, "yaw_rate": 0.05,
                                  "acc": [0.0, 0.1, 9.81]})
    assert imu["roll"] == pytest.approx(0.1) and imu["pitch"] == pytest.approx(-0.2)
    assert imu["yaw"] == pytest.approx(3.0) and imu["acc"] == pytest.approx([0.0, 0.1, 9.81])
    assert roundtrip("/cmd_vel", {"seq": 4, "linear": 0.25, "angular": -1.0}) == \
        {"linear": 0.25, "angular": -1.0}
    assert roundtrip("/laser_alignment/command", {"roll": 0.1, "pitch": -0.1}) == \
        pytest.approx({"roll": 0.1, "pitch": -0.1})
    assert roundtrip("/some/other", {"seq": 3}) == {"seq": 3}  # std_msgs/String, JSON


def test_quaternion_and_euler_are_inverse() -> None:
    for rpy in ((0.0, 0.0, 0.0), (0.3, -0.4, 3.1), (-0.5, 0.5, -math.pi / 2)):
        assert R.euler(R.quaternion(*rpy)) == pytest.approx(rpy, abs=1e-9)


def test_driver_diagnostics_levels() -> None:
    st = DriverStatus("hokuyo_node", "hokuyo")
    assert st.report(0.0)["status"][0]["level"] == ERROR  # not connected
    st.connected = True
    for i in range(40):
        st.frame(0.5 + i / 40)
    report = st.report(1.5)["status"][0]
    assert (report["level"], report["name"], report["hardware_id"]) == \
        (OK, "hokuyo_node: hokuyo", "hokuyo")
    assert report["values"]["rate_hz"] == pytest.approx(40 / 1.5, abs=0.01)
    msg = roundtrip("/diagnostics", st.report(3.0))
    assert msg["status"][0]["level"] == ERROR  # connected, but silent for 1.5 s
    assert msg["status"][0]["message"] == "no data from the device"


def test_the_robot_setting_selects_ros2_and_a_bad_override_is_one_line(tmp_path: Path) -> None:
    assert load_node(ROOT / "models" / "tedusar", "hokuyo_node").middleware in ("zenoh", "ros2")
    text = (ROOT / "models" / "tedusar" / "system.yaml").read_text()
    (tmp_path / "system.yaml").write_text(text.replace("observers:\n",
                                                       "observers:\n  source: {kind: ros2}\n", 1))
    assert load_node(tmp_path, "rviz").middleware == "ros2"
    p = subprocess.run([sys.executable, "-m", "emulator.robot.node", "rviz", str(tmp_path)],
                       capture_output=True, text=True, timeout=60, cwd=ROOT,
                       env={"PATH": "/usr/bin:/bin", "DXBOARD_MIDDLEWARE": "dds"})
    assert p.returncode == 2
    assert p.stderr.strip().splitlines() == [
        "rviz: error: DXBOARD_MIDDLEWARE='dds': use one of zenoh, ros2"], p.stderr


def test_any_message_reads_by_path_and_diagnostics_by_status_name() -> None:
    from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus, KeyValue
    from nav_msgs.msg import Odometry

    from host.observers.sources.ros2_message import RosMessage

    odom = Odometry()
    odom.twist.twist.angular.z = -0.25
    msg = RosMessage(1.0, "/odom", serialize_message(odom), "nav_msgs/msg/Odometry")
    assert msg.number("twist.twist.angular.z") == -0.25
    assert msg.values is not None and msg.values["child_frame_id"] == ""
    diag = DiagnosticArray(status=[DiagnosticStatus(
        level=DiagnosticStatus.WARN, name="jaguar_node: jaguar", hardware_id="jaguar",
        values=[KeyValue(key="temp", value="81.5"), KeyValue(key="mode", value="auto")])])
    d = RosMessage(1.0, "/diagnostics", serialize_message(diag),
                   "diagnostic_msgs/msg/DiagnosticArray")
    assert d.number("jaguar_node: jaguar.level") == 1
    assert d.number("jaguar_node: jaguar.temp") == 81.5
    assert d.values is not None and d.values["jaguar_node: jaguar"]["mode"] == "auto"
    assert d.values["status"][0]["values"] == [{"key": "temp", "value": "81.5"},
                                               {"key": "mode", "value": "auto"}]
    garbage = RosMessage(1.0, "/odom", b"\x00\x01", "nav_msgs/msg/Odometry")
    assert garbage.values is None  # still a message: it counts for the frequency


def test_a_ros2_source_with_a_bad_domain_or_type_is_named_in_the_file(tmp_path: Path) -> None:
    from host.observers.config import ObserverConfigError, load_observers

    (tmp_path / "system.yaml").write_text(
        "observers:\n  source: {kind: ros2, domain: 300, types: {/scan: LaserScan}}\n")
    with pytest.raises(ObserverConfigError) as err:
        load_observers(tmp_path)
    text = "\n".join(str(p) for p in err.value.problems)
    assert "system.yaml:2: domain 300 is not a ROS 2 domain id" in text
    assert "types: {/scan: sensor_msgs/msg/LaserScan}" in text
    (tmp_path / "system.yaml").write_text(
        "observers:\n  source: {kind: ros2, domain: 7}\n"
        "  topics: {/scan: {rate: 40, tolerance: 10, window: 0.5}}\n")
    spec = load_observers(tmp_path).source
    assert (spec.kind, spec.domain, spec.types) == ("ros2", 7, ())


def test_the_daemon_takes_the_middleware_from_the_command_line() -> None:
    from host.daemon.core import load_robot

    tedusar = ROOT / "models" / "tedusar"
    assert load_robot(tedusar).observers.source.kind == "zenoh"  # the model's setting
    assert load_robot(tedusar, middleware="ros2").observers.source.kind == "ros2"
    from host.daemon.core import _middleware_env
    from host.observers.config import SourceSpec
    assert _middleware_env(SourceSpec()) == {"DXBOARD_MIDDLEWARE": "zenoh"}
    assert _middleware_env(SourceSpec("ros2", domain=7)) == {  # the nodes it starts follow it
        "DXBOARD_MIDDLEWARE": "ros2", "ROS_DOMAIN_ID": "7"}
    p = subprocess.run([sys.executable, "-m", "host.cli", "run", str(tedusar), "--emulate",
                        "--middleware", "dds"], capture_output=True, text=True, timeout=60,
                       cwd=ROOT)
    assert p.returncode == 2
    assert "--middleware: invalid choice: 'dds'" in p.stderr
