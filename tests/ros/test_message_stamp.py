"""The frequency observer reads every message's stamp; on ROS 2 it comes straight from the CDR
bytes of the header, never by deserialising the message (a 4 MB /map converted to Python for
each message starved the daemon's loop: it could not even stop on SIGINT)."""

from __future__ import annotations

from nav_msgs.msg import OccupancyGrid
from rclpy.serialization import serialize_message
from std_msgs.msg import String

from host.observers.sources.ros2_message import RosMessage


def test_the_stamp_is_read_from_the_bytes_without_deserialising() -> None:
    grid = OccupancyGrid()
    grid.header.stamp.sec, grid.header.stamp.nanosec = 1700000000, 250_000_000
    grid.info.width = grid.info.height = 2000
    grid.data = [0] * (2000 * 2000)
    msg = RosMessage(0.0, "/map", serialize_message(grid), "nav_msgs/msg/OccupancyGrid")
    assert msg.stamp == 1700000000.25
    assert "values" not in msg.__dict__  # nothing was deserialised for it


def test_a_type_without_a_header_has_no_stamp() -> None:
    msg = RosMessage(0.0, "/x", serialize_message(String(data="hi")), "std_msgs/msg/String")
    assert msg.stamp is None
    assert msg.values == {"data": "hi"}
