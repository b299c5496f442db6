"""The virtual robot's topics as standard ROS 2 messages: the JSON frames <-> message objects.

The nodes compute on plain dicts (``emulator.robot.behaviours``), as in Zenoh mode; in ROS 2
mode each topic has a standard type and two conversions, ``to_msg(values, stamp)`` for what a
node publishes and ``from_msg(msg)`` for what it subscribes::

    /scan                     sensor_msgs/LaserScan      ranges in m (the device sends mm)
    /odom                     nav_msgs/Odometry          pose (x, y, yaw), twist (speed, yaw_rate)
    /imu_data                 sensor_msgs/Imu            orientation (roll, pitch, yaw),
                                                         angular_velocity.z, linear_acceleration
    /joy                      sensor_msgs/Joy            axes, buttons
    /cmd_vel                  geometry_msgs/Twist        linear.x, angular.z
    /map                      nav_msgs/OccupancyGrid     resolution, width, height (unknown cells)
    /slam_out_pose            geometry_msgs/PoseStamped  x, y, yaw
    /laser_alignment/state    sensor_msgs/JointState     joints roll, pitch (position)
    /laser_alignment/command  sensor_msgs/JointState     joints roll, pitch (target position)
    /diagnostics              diagnostic_msgs/DiagnosticArray  (``emulator.robot.driver_status``)
    any other topic           std_msgs/String            the dict as JSON

Frame ids follow REP 105 (``odom``, ``base_link``, ``laser``, ``imu_link``, ``map``). The
``seq`` of a frame is dropped: ROS 2 headers carry a stamp, not a sequence number.
"""

from __future__ import annotations

import array
import json
import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

from builtin_interfaces.msg import Time
from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus, KeyValue
from geometry_msgs.msg import PoseStamped, Quaternion, Twist
from nav_msgs.msg import OccupancyGrid, Odometry
from sensor_msgs.msg import Imu, JointState, Joy, LaserScan
from std_msgs.msg import String

ToMsg = Callable[[dict[str, Any], Time], Any]
FromMsg = Callable[[Any], dict[str, Any]]

LIDAR_RANGE_MIN = 0.1  # m, UTM-30LX
LIDAR_SCAN_TIME = 0.025  # s, 40 Hz


@dataclass(frozen=True)
class TopicType:
    type: Any  # the message class
    to_msg: ToMsg
    from_msg: FromMsg


def _f(values: dict[str, Any], key: str, default: float = 0.0) -> float:
    v = values.get(key)
    return float(v) if isinstance(v, int | float) and not isinstance(v, bool) else default


def quaternion(roll: float, pitch: float, yaw: float) -> Quaternion:
    cr, sr = math.cos(roll / 2), math.sin(roll / 2)
    cp, sp = math.cos(pitch / 2), math.sin(pitch / 2)
    cy, sy = math.cos(yaw / 2), math.sin(yaw / 2)
    return Quaternion(x=sr * cp * cy - cr * sp * sy, y=cr * sp * cy + sr * cp * sy,
                      z=cr * cp * sy - sr * sp * cy, w=cr * cp * cy + sr * sp * sy)


def euler(q: Quaternion) -> tuple[float, float, float]:
    """(roll, pitch, yaw) of a unit quaternion."""
    roll = math.atan2(2 * (q.w * q.x + q.y * q.z), 1 - 2 * (q.x * q.x + q.y * q.y))
    pitch = math.asin(max(-1.0, min(1.0, 2 * (q.w * q.y - q.z * q.x))))
    yaw = math.atan2(2 * (q.w * q.z + q.x * q.y), 1 - 2 * (q.y * q.y + q.z * q.z))
    return roll, pitch, yaw


def _scan(values: dict[str, Any], stamp: Time) -> LaserScan:
    msg = LaserScan()
    msg.header.stamp, msg.header.frame_id = stamp, "laser"
    ranges = [r / 1000.0 for r in values.get("ranges_mm") or ()]
    inc = _f(values, "angle_increment")
    msg.angle_min = _f(values, "angle_min")
    msg.angle_max = msg.angle_min + inc * max(0, len(ranges) - 1)
    msg.angle_increment = inc
    msg.scan_time = LIDAR_SCAN_TIME
    msg.time_increment = LIDAR_SCAN_TIME / max(1, len(ranges))
    msg.range_min = LIDAR_RANGE_MIN
    msg.range_max = _f(values, "range_max_mm") / 1000.0
    msg.ranges = array.array("f", ranges)
    return msg


def _scan_values(msg: LaserScan) -> dict[str, Any]:
    return {"angle_min": float(msg.angle_min), "angle_increment": float(msg.angle_increment),
            "range_max_mm": round(msg.range_max * 1000),
            "ranges_mm": [round(r * 1000) for r in msg.ranges]}


def _odom(values: dict[str, Any], stamp: Time) -> Odometry:
    msg = Odometry()
    msg.header.stamp, msg.header.frame_id, msg.child_frame_id = stamp, "odom", "base_link"
    msg.pose.pose.position.x = _f(values, "x")
    msg.pose.pose.position.y = _f(values, "y")
    msg.pose.pose.orientation = quaternion(0.0, 0.0, _f(values, "yaw"))
    msg.twist.twist.linear.x = _f(values, "speed")
    msg.twist.twist.angular.z = _f(values, "yaw_rate")
    return msg


def _odom_values(msg: Odometry) -> dict[str, Any]:
    p = msg.pose.pose
    return {"x": p.position.x, "y": p.position.y, "yaw": euler(p.orientation)[2],
            "speed": msg.twist.twist.linear.x, "yaw_rate": msg.twist.twist.angular.z}


def _imu(values: dict[str, Any], stamp: Time) -> Imu:
    msg = Imu()
    msg.header.stamp, msg.header.frame_id = stamp, "imu_link"
    msg.orientation = quaternion(_f(values, "roll"), _f(values, "pitch"), _f(values, "yaw"))
    msg.angular_velocity.z = _f(values, "yaw_rate")
    acc = values.get("acc")
    if isinstance(acc, list) and len(acc) == 3:
        a = msg.linear_acceleration
        a.x, a.y, a.z = (float(v) for v in acc)
    return msg


def _imu_values(msg: Imu) -> dict[str, Any]:
    roll, pitch, yaw = euler(msg.orientation)
    a = msg.linear_acceleration
    return {"roll": roll, "pitch": pitch, "yaw": yaw, "yaw_rate": msg.angular_velocity.z,
            "acc": [a.x, a.y, a.z]}


def _joy(values: dict[str, Any], stamp: Time) -> Joy:
    msg = Joy()
    msg.header.stamp = stamp
    msg.axes = array.array("f", (float(a) for a in values.get("axes") or ()))
    msg.buttons = array.array("i", (int(b) for b in values.get("buttons") or ()))
    return msg


def _joy_values(msg: Joy) -> dict[str, Any]:
    return {"axes": [float(a) for a in msg.axes], "buttons": [int(b) for b in msg.buttons]}


def _twist(values: dict[str, Any], stamp: Time) -> Twist:
    msg = Twist()
    msg.linear.x = _f(values, "linear")
    msg.angular.z = _f(values, "angular")
    return msg


def _twist_values(msg: Twist) -> dict[str, Any]:
    return {"linear": msg.linear.x, "angular": msg.angular.z}


def _map(values: dict[str, Any], stamp: Time) -> OccupancyGrid:
    msg = OccupancyGrid()
    msg.header.stamp, msg.header.frame_id = stamp, "map"
    info = msg.info
    info.map_load_time = stamp
    info.resolution = _f(values, "resolution", 0.05)
    info.width, info.height = int(_f(values, "width")), int(_f(values, "height"))
    info.origin.position.x = -info.width * info.resolution / 2
    info.origin.position.y = -info.height * info.resolution / 2
    info.origin.orientation.w = 1.0
    msg.data = array.array("b", b"\xff" * (info.width * info.height))  # -1: unknown
    return msg


def _map_values(msg: OccupancyGrid) -> dict[str, Any]:
    i = msg.info
    return {"resolution": i.resolution, "width": i.width, "height": i.height}


def _pose(values: dict[str, Any], stamp: Time) -> PoseStamped:
    msg = PoseStamped()
    msg.header.stamp, msg.header.frame_id = stamp, "map"
    msg.pose.position.x = _f(values, "x")
    msg.pose.position.y = _f(values, "y")
    msg.pose.orientation = quaternion(0.0, 0.0, _f(values, "yaw"))
    return msg


def _pose_values(msg: PoseStamped) -> dict[str, Any]:
    p = msg.pose
    return {"x": p.position.x, "y": p.position.y, "yaw": euler(p.orientation)[2]}


def _joints(values: dict[str, Any], stamp: Time) -> JointState:
    msg = JointState()
    msg.header.stamp = stamp
    msg.name = ["roll", "pitch"]
    msg.position = [_f(values, "roll"), _f(values, "pitch")]
    return msg


def _joints_values(msg: JointState) -> dict[str, Any]:
    return {str(n): float(p) for n, p in zip(msg.name, msg.position, strict=False)}


def _diagnostics(values: dict[str, Any], stamp: Time) -> DiagnosticArray:
    msg = DiagnosticArray()
    msg.header.stamp = stamp
    for s in values.get("status") or ():
        msg.status.append(DiagnosticStatus(
            level=bytes([int(s["level"])]), name=str(s["name"]),
            message=str(s.get("message", "")), hardware_id=str(s.get("hardware_id", "")),
            values=[KeyValue(key=str(k), value=str(v)) for k, v in s.get("values", {}).items()]))
    return msg


def _diagnostics_values(msg: DiagnosticArray) -> dict[str, Any]:
    return {"status": [{"level": s.level[0] if isinstance(s.level, bytes) else int(s.level),
                        "name": s.name, "message": s.message, "hardware_id": s.hardware_id,
                        "values": {kv.key: kv.value for kv in s.values}} for s in msg.status]}


def _string(values: dict[str, Any], stamp: Time) -> String:
    return String(data=json.dumps(values, separators=(",", ":")))


def _string_values(msg: String) -> dict[str, Any]:
    try:
        obj = json.loads(msg.data)
    except ValueError:
        return {}
    return obj if isinstance(obj, dict) else {}


TOPICS: dict[str, TopicType] = {
    "/scan": TopicType(LaserScan, _scan, _scan_values),
    "/odom": TopicType(Odometry, _odom, _odom_values),
    "/imu_data": TopicType(Imu, _imu, _imu_values),
    "/joy": TopicType(Joy, _joy, _joy_values),
    "/cmd_vel": TopicType(Twist, _twist, _twist_values),
    "/map": TopicType(OccupancyGrid, _map, _map_values),
    "/slam_out_pose": TopicType(PoseStamped, _pose, _pose_values),
    "/laser_alignment/state": TopicType(JointState, _joints, _joints_values),
    "/laser_alignment/command": TopicType(JointState, _joints, _joints_values),
    "/diagnostics": TopicType(DiagnosticArray, _diagnostics, _diagnostics_values),
}
GENERIC = TopicType(String, _string, _string_values)


def topic_type(topic: str) -> TopicType:
    return TOPICS.get(topic, GENERIC)
