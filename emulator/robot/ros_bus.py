"""The robot's topics on ROS 2, for the node processes: one rclpy node, standard message types.

``RosBus(name)`` has the interface of ``emulator.robot.bus.Bus`` (``publish(topic, values)``,
``subscribe(topic, handler)``, ``close()``), so a node's behaviour does not know which
middleware carries its topics; ``emulator.robot.ros_msgs`` turns the dicts into standard
messages and back. The process is one ROS 2 node named after its component (``hokuyo_node``),
in its own rclpy ``Context`` on the domain of ``$ROS_DOMAIN_ID``. rclpy runs in a thread of its
own with its own executor; subscription callbacks hand each converted message to the asyncio
loop in order, through the bus's batching inbox (``emulator.robot.bus.inbox_for``: one wakeup
per batch, not one per message). rclpy's signal handlers are not installed: the
node program's asyncio loop owns SIGTERM and SIGINT.

QoS: reliable, keep last 10 (the default profile), which every default subscriber matches.

Stamps: a message's ``header.stamp`` is when its data was taken, as a real driver stamps it
(urg_node stamps a scan with its acquisition time, the device's clock mapped onto the host's):

- a driver's message (its values carry the device frame's ``t_ms``, the emulator's clock:
  ``emulator.robot.devices``) gets the device's time mapped onto the node's ROS clock by an
  offset ``DeviceClock`` estimates from the frames: the smallest arrival-minus-device-time seen
  since the device's clock (re)started (its ``t_ms`` or ``seq`` went back). Stamps so keep the
  device's spacing whatever held up the driver (a burst read after it was descheduled carries
  the times its frames were taken), and never lie in the future of the node's clock;
- every other message (a node computing on its inputs: hector, teleop) is stamped when it is
  published, as theirs are.
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
from rclpy.time import Time

from emulator.inbox import Inbox
from emulator.robot.bus import Delivery, Handler, inbox_for
from emulator.robot.ros_msgs import topic_type

log = logging.getLogger(__name__)

DEPTH = 10


def _number(v: Any) -> float | None:
    return float(v) if isinstance(v, int | float) and not isinstance(v, bool) else None


class DeviceClock:
    """A device's clock (``t_ms``) mapped onto a node's (ns): by the smallest offset seen."""

    def __init__(self) -> None:
        self.offset_ns: int | None = None  # node time - device time, the least seen
        self._last: tuple[float, float] | None = None  # the last frame's (t_ms, seq)

    def stamp(self, t_ms: float, seq: float | None, now_ns: int) -> int:
        """The node-clock time (ns) of a frame taken at ``t_ms``, read at ``now_ns``."""
        last = self._last
        if last is not None and (t_ms < last[0] or (seq is not None and seq < last[1])):
            log.info("the device's clock restarted (t_ms %s after %s): offset afresh",
                     t_ms, last[0])
            self.offset_ns = None
        self._last = (t_ms, seq if seq is not None else float("-inf"))
        device_ns = round(t_ms * 1e6)
        offset = now_ns - device_ns
        if self.offset_ns is None or offset < self.offset_ns:
            self.offset_ns = offset
        return device_ns + self.offset_ns


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
        self._clocks: dict[str, DeviceClock] = {}  # per topic a driver publishes
        self._inbox: Inbox[Delivery] | None = None
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
        pub.publish(kind.to_msg(values, self.stamp(topic, values)))

    def stamp(self, topic: str, values: dict[str, Any]) -> Any:
        """The header stamp of ``values`` (see the module docstring)."""
        now = self.node.get_clock().now()
        t_ms = _number(values.get("t_ms"))
        if t_ms is None:
            return now.to_msg()
        clock = self._clocks.get(topic)
        if clock is None:
            clock = self._clocks[topic] = DeviceClock()
        ns = clock.stamp(t_ms, _number(values.get("seq")), now.nanoseconds)
        return Time(nanoseconds=ns, clock_type=now.clock_type).to_msg()

    def subscribe(self, topic: str, handler: Handler) -> None:
        """Call ``handler(topic, values)`` on the running loop for every message."""
        if self._inbox is None:
            self._inbox = inbox_for(asyncio.get_running_loop())
        inbox = self._inbox
        kind = topic_type(topic)

        def on_msg(msg: Any) -> None:  # on the executor's thread
            inbox.put((handler, topic, kind.from_msg(msg)))

        self.node.create_subscription(kind.type, topic, on_msg, DEPTH)

    def close(self) -> None:
        if not self.context.ok():
            return
        self.executor.shutdown(timeout_sec=2.0)
        self.node.destroy_node()
        self.context.try_shutdown()
        self._thread.join(timeout=5.0)
