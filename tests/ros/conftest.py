"""ROS 2 in the tests: a DDS domain of the test's own, and a plain rclpy peer that knows no dxboard.

``domain`` claims a ``ROS_DOMAIN_ID`` for one test (``tests.ros.domain``: from the test
process's pid, held by a lock file per domain for the test's duration, so two suites beside
each other, or two tests of one, never share a domain); discovery stays on this machine
(``ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST``). ``env`` is the process
environment with that domain, for the subprocesses a test starts.

``Peer`` is the independent observer: plain rclpy and the standard message packages, nothing
imported from dxboard. It runs its own context and executor in a thread, records every message
of the topics it is told (arrival time, message object), and reads the ROS 2 graph.
"""

from __future__ import annotations

import contextlib
import json
import os
import threading
import time
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest
import rclpy
from rclpy.context import Context
from rclpy.executors import ExternalShutdownException, SingleThreadedExecutor
from rclpy.node import Node
from rclpy.signals import SignalHandlerOptions

from tests.robot import conftest as robot_fixtures
from tests.robot.conftest import ROOT, Nodes, Robot
from tests.ros.domain import claim_domain, domain_env
from tests.wait import wait_until

robot_dir = robot_fixtures.robot_dir  # the virtual robot's fixtures, shared
robot = robot_fixtures.robot


@pytest.fixture
def domain(monkeypatch: pytest.MonkeyPatch) -> Iterator[int]:
    with claim_domain() as d:
        for name, value in domain_env(d).items():
            monkeypatch.setenv(name, value)
        yield d


@pytest.fixture
def env(domain: int) -> dict[str, str]:
    return {**os.environ, **domain_env(domain)}


class Peer:
    """A plain rclpy node in a thread: records messages, reads the graph."""

    def __init__(self, domain: int, name: str = "independent_peer") -> None:
        self.context = Context()
        rclpy.init(context=self.context, domain_id=domain,
                   signal_handler_options=SignalHandlerOptions.NO)
        self.node = Node(name, context=self.context)
        self.executor = SingleThreadedExecutor(context=self.context)
        self.executor.add_node(self.node)
        self.lock = threading.Lock()
        self.seen: list[tuple[float, str, Any]] = []
        self.thread = threading.Thread(target=self._spin, daemon=True)
        self.thread.start()

    def _spin(self) -> None:
        with contextlib.suppress(ExternalShutdownException):
            self.executor.spin()

    def listen(self, topic: str, msg_type: Any) -> None:
        def on(msg: Any) -> None:
            with self.lock:
                self.seen.append((time.monotonic(), topic, msg))
        self.node.create_subscription(msg_type, topic, on, 50)

    def messages(self, topic: str, since: float = 0.0) -> list[Any]:
        with self.lock:
            return [m for t, k, m in self.seen if k == topic and t >= since]

    def collect(self, topic: str, n: int, timeout: float = 60.0) -> list[Any]:
        t0 = time.monotonic()
        return wait_until(lambda: self.messages(topic, t0)[:n]
                          if len(self.messages(topic, t0)) >= n else [],
                          timeout, f"{n} messages on {topic}",
                          show=lambda: f"{len(self.messages(topic, t0))} messages")

    def wait_for(self, probe: Any, what: str, timeout: float = 60.0) -> Any:
        return wait_until(probe, timeout, what)

    def nodes(self) -> set[str]:
        return {n for n, _ in self.node.get_node_names_and_namespaces()}

    def close(self) -> None:
        self.executor.shutdown(timeout_sec=2.0)
        self.node.destroy_node()
        self.context.try_shutdown()
        self.thread.join(timeout=5.0)


@pytest.fixture
def peer(domain: int) -> Iterator[Peer]:
    p = Peer(domain)
    yield p
    p.close()


def stamp_ms(msg: Any) -> float:
    """The sender's time of a stamped message (ms)."""
    return float(msg.header.stamp.sec * 1000 + msg.header.stamp.nanosec / 1e6)


class RosNodes(Nodes):
    """The virtual robot's node processes in ROS 2 mode, on the test's domain."""

    def __init__(self, system_dir: Path, robot: Robot, env: dict[str, str]) -> None:
        self.system_dir = system_dir
        self.env = {**env, "DXBOARD_MIDDLEWARE": "ros2",
                    "DXBOARD_DEVICES": json.dumps(robot.devices), "PYTHONPATH": str(ROOT)}
        self.children = {}

    def start_managed(self, name: str) -> None:
        """Start driver ``name`` as a managed (lifecycle) node."""
        self.start(name, extra=("--managed",))


@pytest.fixture
def ros_nodes(robot_dir: Path, robot: Robot, env: dict[str, str]) -> Iterator[RosNodes]:
    n = RosNodes(robot_dir, robot, env)
    yield n
    n.stop_all()

