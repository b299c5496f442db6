"""The virtual robot's nodes in ROS 2 mode, read by a plain rclpy peer that knows no dxboard."""

from __future__ import annotations

from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus
from geometry_msgs.msg import PoseStamped, Twist
from nav_msgs.msg import OccupancyGrid, Odometry
from sensor_msgs.msg import Imu, Joy, LaserScan

from tests.rates import assert_rate
from tests.robot.conftest import Robot
from tests.ros.conftest import Peer, RosNodes, stamp_ms


def _level(msg: DiagnosticArray, name: str) -> int | None:
    for s in msg.status:
        if s.name == name:
            return s.level[0] if isinstance(s.level, bytes) else int(s.level)
    return None


def test_hokuyo_node_publishes_laserscan_at_40_hz_and_its_diagnostics_follow_a_hang(
        robot: Robot, peer: Peer, ros_nodes: RosNodes) -> None:
    peer.listen("/scan", LaserScan)
    peer.listen("/diagnostics", DiagnosticArray)
    ros_nodes.start("hokuyo_node")
    peer.wait_for(lambda: "hokuyo_node" in peer.nodes(), "hokuyo_node in the ROS 2 graph")
    name = "hokuyo_node: hokuyo"
    peer.wait_for(lambda: any(_level(m, name) == DiagnosticStatus.ERROR[0]
                              for m in peer.messages("/diagnostics")),
                  "ERROR while the Hokuyo is off")
    robot.board("on", "hokuyo")
    scans = peer.collect("/scan", 80)
    assert_rate([stamp_ms(m) for m in scans], 40, "/scan")
    scan = scans[-1]
    assert len(scan.ranges) == 1081
    assert scan.header.frame_id == "laser"
    assert min(scan.ranges) >= 0.1 and max(scan.ranges) <= scan.range_max == 30.0
    assert abs(scan.angle_max - scan.angle_min - 1080 * scan.angle_increment) < 1e-4
    peer.wait_for(lambda: any(_level(m, name) == DiagnosticStatus.OK[0]
                              for m in peer.messages("/diagnostics")[-1:]),
                  "OK while scans arrive")
    status = next(s for s in peer.messages("/diagnostics")[-1].status if s.name == name)
    assert status.hardware_id == "hokuyo"
    assert {kv.key for kv in status.values} >= {"frames", "rate_hz", "connected"}
    robot.inject("hokuyo", "hang")
    peer.wait_for(lambda: any(_level(m, name) == DiagnosticStatus.ERROR[0]
                              and m.status[0].message == "no data from the device"
                              for m in peer.messages("/diagnostics")[-1:]),
                  "ERROR after the hang")
    assert ros_nodes.stop("hokuyo_node") == 0


def test_teleop_base_imu_and_mapping_speak_standard_messages(
        robot: Robot, peer: Peer, ros_nodes: RosNodes) -> None:
    for topic, kind in (("/joy", Joy), ("/cmd_vel", Twist), ("/odom", Odometry),
                        ("/imu_data", Imu), ("/map", OccupancyGrid),
                        ("/slam_out_pose", PoseStamped)):
        peer.listen(topic, kind)
    robot.board("on", "jaguar")
    robot.board("on", "hokuyo")
    ros_nodes.start("joy_node", "jaguar_teleop_node", "jaguar_node", "imu_node",
                    "hokuyo_node", "hector_mapping")
    imu = peer.collect("/imu_data", 200)
    assert_rate([stamp_ms(m) for m in imu], 100, "/imu_data")
    odom = peer.collect("/odom", 40)
    assert_rate([stamp_ms(m) for m in odom], 20, "/odom")
    assert odom[-1].header.frame_id == "odom" and odom[-1].child_frame_id == "base_link"
    joy = peer.collect("/joy", 5)
    assert len(joy[-1].axes) == 2
    cmds = peer.collect("/cmd_vel", 5)
    assert all(abs(c.linear.x) <= 0.5 and abs(c.angular.z) <= 1.0 for c in cmds)  # teleop's
    pose = peer.collect("/slam_out_pose", 5)[-1]
    assert pose.header.frame_id == "map"
    grid = peer.collect("/map", 1, timeout=90)[-1]
    assert (grid.info.width, grid.info.height) == (2048, 2048)
    assert len(grid.data) == 2048 * 2048
    for name in ("joy_node", "jaguar_teleop_node", "jaguar_node", "imu_node",
                 "hokuyo_node", "hector_mapping"):
        assert ros_nodes.stop(name) == 0, name
