"""The robot's topics on ROS 2, for the node processes: one rclpy node, standard message types.

``RosBus(name)`` has the interface of ``emulator.robot.bus.Bus`` (``publish(topic, values)``,
``subscribe(topic, handler)``, ``close()``), so a node's behaviour does not know which
middleware carries its topics; ``emulator.robot.ros_msgs`` turns the dicts into standard
messages and back. The process is one ROS 2 node named after its component (``hokuyo_node``),
in its own rclpy ``Context`` on the domain of ``$ROS_DOMAIN_ID``. rclpy runs in a thread of its
own with its own executor; subscription callbacks hand each converted message to the asyncio
loop with ``call_soon_threadsafe``, in order. rclpy's signal handlers are not installed: the
node program's asyncio loop owns SIGTERM and SIGINT.

QoS: reliable, keep last 10 (the default profile), which every default subscriber matches.
"""

from __future__ import annotations

import asyncio
import contextlib
import logging
import threading
from typing import Any

import rclpy
from rclpy.context import Context
from rclpy.executors import ExternalShutdownException, SingleThreadedExecutor
from rclpy.node import Node
from rclpy.publisher import Publisher
from rclpy.signals import SignalHandlerOptions

from emulator.robot.bus import Handler
from emulator.robot.ros_msgs import topic_type

log = logging.getLogger(__name__)

DEPTH = 10


class RosBus:
    ros = True

    def __init__(self, name: str, node: Node | None = None, context: Context | None = None
                 ) -> None:
        """A node ``name`` in a fresh context, or ``node`` (made in ``context``) when given:
        a lifecycle node is built by its caller."""
        if node is None:
            context = Context()
            rclpy.init(context=context, signal_handler_options=SignalHandlerOptions.NO)
            node = Node(name, context=context)
        assert context is not None
        self.context = context
        self.node = node
        self._pubs: dict[str, Publisher[Any]] = {}
        self.executor = SingleThreadedExecutor(context=context)
        self.executor.add_node(node)
        self._thread = threading.Thread(target=self._spin, name=f"rclpy-{name}", daemon=True)
        self._thread.start()

    def _spin(self) -> None:
        with contextlib.suppress(ExternalShutdownException):
            self.executor.spin()

    def publish(self, topic: str, values: dict[str, Any]) -> None:
        kind = topic_type(topic)
        pub = self._pubs.get(topic)
        if pub is None:
            pub = self._pubs[topic] = self.node.create_publisher(kind.type, topic, DEPTH)
        pub.publish(kind.to_msg(values, self.node.get_clock().now().to_msg()))

    def subscribe(self, topic: str, handler: Handler) -> None:
        """Call ``handler(topic, values)`` on the running loop for every message."""
        loop = asyncio.get_running_loop()
        kind = topic_type(topic)

        def on_msg(msg: Any) -> None:  # on the executor's thread
            values = kind.from_msg(msg)
            with contextlib.suppress(RuntimeError):  # the loop closed while rclpy delivered
                loop.call_soon_threadsafe(handler, topic, values)

        self.node.create_subscription(kind.type, topic, on_msg, DEPTH)

    def close(self) -> None:
        if not self.context.ok():
            return
        self.executor.shutdown(timeout_sec=2.0)
        self.node.destroy_node()
        self.context.try_shutdown()
        self._thread.join(timeout=5.0)
