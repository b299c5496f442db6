"""Each observer kind over ROS 2: the daemon's ROS 2 source fed by the virtual robot's ROS 2
node processes (real rclpy nodes, their own processes, the test's own DDS domain)."""

from __future__ import annotations

from typing import Any

from host.diagnosis.observations import Observation
from host.observers.base import Update
from host.observers.hub import ObserverHub
from host.observers.sources.ros2 import Ros2Source
from host.observers.sources.ros2_graph import GraphObserver
from host.observers.topics import FrequencyObserver
from host.observers.values import DiagnosticObserver, Threshold, TrendObserver, ValueRef
from tests.robot.conftest import Robot
from tests.ros.conftest import RosNodes
from tests.wait import wait_until_async


class Seen:
    """The hub's sink: the latest sign of every atom (None: retracted)."""

    def __init__(self) -> None:
        self.state: dict[str, bool | None] = {}

    def __call__(self, updates: list[Update]) -> None:
        for u in updates:
            if isinstance(u, Observation):
                self.state[u.literal.atom] = u.literal.positive
            else:
                self.state[u.atom] = None

    async def until(self, atom: str, value: bool | None, timeout: float = 60.0) -> None:
        await wait_until_async(lambda: atom in self.state and self.state[atom] is value,
                               timeout, f"{atom} = {value}", show=lambda: self.state)


async def test_frequency_graph_trend_and_diagnostic_observers_over_ros2(
        domain: int, robot: Robot, ros_nodes: RosNodes) -> None:
    observers: list[Any] = [
        FrequencyObserver("/imu_data", rate=100, tolerance=25, window=0.5),
        GraphObserver("imu_node"),
        TrendObserver(ValueRef("imu_yaw_rate", "/imu_data", "angular_velocity.z"),
                      window=1.0, slope=0.05),
        TrendObserver(ValueRef("odom_x", "/odom", "pose.pose.position.x"), window=1.0,
                      slope=0.5),
        DiagnosticObserver("/diagnostics", [
            Threshold("hokuyo_node: hokuyo.level", "ok(hokuyo)", max=0),
            Threshold("hokuyo_node: hokuyo.rate_hz", "ok(/scan)", min=30, max=50)]),
    ]
    seen = Seen()
    hub = ObserverHub(observers, seen)
    source = Ros2Source(domain)  # types from the graph: the nodes start after it
    await hub.start(source)
    try:
        ros_nodes.start("imu_node", "hokuyo_node")
        await seen.until("ok(/imu_data)", True)
        await seen.until("running(imu_node)", True)
        await seen.until("const(imu_yaw_rate)", True)  # the base is off: no turn
        await seen.until("ok(hokuyo)", False)  # the Hokuyo is not powered
        robot.board("on", "hokuyo")
        await seen.until("ok(hokuyo)", True)
        await seen.until("ok(/scan)", True)
        assert "const(odom_x)" not in seen.state  # no /odom publisher: never subscribed
        ros_nodes.stop("imu_node")
        await seen.until("ok(/imu_data)", False)  # silence, at once
        await seen.until("running(imu_node)", False)  # the node left the graph
        robot.inject("hokuyo", "hang")
        await seen.until("ok(hokuyo)", False)
    finally:
        await hub.close()
        source.close()
