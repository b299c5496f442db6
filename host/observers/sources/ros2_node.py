"""One rclpy node in a thread of its own: its own context, its own executor, never the loop's.

``RosNode(name, domain_id)`` initialises a fresh rclpy ``Context`` (on ``domain_id``, or
``$ROS_DOMAIN_ID`` when None), makes the node and spins a ``SingleThreadedExecutor`` in a
daemon thread, so DDS never blocks the daemon's asyncio loop and two of them (a source and a
publisher, or two daemons in one test) never share state. rclpy's signal handlers are not
installed: the daemon owns SIGINT and SIGTERM. Entities may be created from the loop's thread
(rclpy wakes the executor); callbacks run on the executor's thread, so whoever hands data to
the loop does it with ``call_soon_threadsafe``. ``close()`` is idempotent.
"""

from __future__ import annotations

import contextlib
import logging
import threading

import rclpy
from rclpy.context import Context
from rclpy.executors import ExternalShutdownException, SingleThreadedExecutor
from rclpy.node import Node
from rclpy.signals import SignalHandlerOptions

log = logging.getLogger(__name__)


class RosNode:
    def __init__(self, name: str, domain_id: int | None = None) -> None:
        self.context = Context()
        rclpy.init(context=self.context, domain_id=domain_id,
                   signal_handler_options=SignalHandlerOptions.NO)
        self.node = Node(name, context=self.context)
        self.executor = SingleThreadedExecutor(context=self.context)
        self.executor.add_node(self.node)
        self._thread = threading.Thread(target=self._spin, name=f"rclpy-{name}", daemon=True)
        self._thread.start()
        log.info("ROS 2 node %s on domain %d", name, self.context.get_domain_id())

    def _spin(self) -> None:
        with contextlib.suppress(ExternalShutdownException):
            self.executor.spin()

    def close(self) -> None:
        if not self.context.ok():
            return
        self.executor.shutdown(timeout_sec=2.0)
        self.node.destroy_node()
        self.context.try_shutdown()
        self._thread.join(timeout=5.0)
