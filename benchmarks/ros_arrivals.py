"""An independent ROS 2 peer that keeps every arrival time of the robot's topics (benchmarks).

The Zenoh robot's benchmarks watch its topics through a Zenoh peer of their own
(``benchmarks.loop.TopicClock``); on the ROS 2 robot (``dxboard run --middleware ros2``, what
``make run`` starts) this is its counterpart: plain rclpy and the standard message packages,
nothing of dxboard's ROS 2 source, in a context and an executor thread of its own on the
robot's DDS domain. Every message of the topics it is told is stamped on arrival with
CLOCK_MONOTONIC, as the daemon's journal stamps its entries (``mono``), so that a hang's
silence limit as applied, and the gap around a false verdict, can be read off. Subscriptions
are best effort (they match reliable and best-effort publishers alike) and take the raw bytes
(no decoding: the peer should cost its machine as little as it can).
"""

from __future__ import annotations

import contextlib
import threading

import rclpy
from diagnostic_msgs.msg import DiagnosticArray
from geometry_msgs.msg import Twist
from nav_msgs.msg import OccupancyGrid, Odometry
from rclpy.context import Context
from rclpy.executors import ExternalShutdownException, SingleThreadedExecutor
from rclpy.node import Node
from rclpy.qos import QoSHistoryPolicy, QoSProfile, QoSReliabilityPolicy
from rclpy.signals import SignalHandlerOptions
from sensor_msgs.msg import Imu, LaserScan
from std_msgs.msg import String

from benchmarks.loop import arrival_stamper, gap_around

# the virtual robot's types (emulator/robot/ros_msgs.py documents them); others are strings
TYPES: dict[str, type] = {"/scan": LaserScan, "/imu_data": Imu, "/odom": Odometry,
                          "/cmd_vel": Twist, "/map": OccupancyGrid,
                          "/diagnostics": DiagnosticArray}
QOS = QoSProfile(history=QoSHistoryPolicy.KEEP_LAST, depth=100,
                 reliability=QoSReliabilityPolicy.BEST_EFFORT)


class RosArrivals:
    """Arrival times of ``topics`` on ROS 2 domain ``domain``: ``last[topic]`` (the latest)
    and ``times[topic]`` (all, in order); ``close()`` ends the peer."""

    def __init__(self, domain: int, topics: list[str]) -> None:
        self.last: dict[str, float] = {}
        self.times: dict[str, list[float]] = {t: [] for t in topics}
        self.context = Context()
        rclpy.init(context=self.context, domain_id=domain,
                   signal_handler_options=SignalHandlerOptions.NO)
        self.node = Node("benchmark_arrivals", context=self.context)
        for t in topics:
            on = arrival_stamper(self.last, self.times[t], t)
            self.node.create_subscription(TYPES.get(t, String), t, on, QOS, raw=True)
        self.executor = SingleThreadedExecutor(context=self.context)
        self.executor.add_node(self.node)
        self.thread = threading.Thread(target=self._spin, daemon=True)
        self.thread.start()

    def _spin(self) -> None:
        with contextlib.suppress(ExternalShutdownException):
            self.executor.spin()

    def gap(self, topic: str, mono: float) -> tuple[float, float] | None:
        return gap_around(self.times.get(topic, []), mono)

    def close(self) -> None:
        self.executor.shutdown(timeout_sec=2.0)
        self.node.destroy_node()
        self.context.try_shutdown()
        self.thread.join(timeout=5.0)
