"""Watching a running ROS 2 robot: every topic's arrivals and the graph, into a ``Recording``.

``RosWatcher(rec)`` is an rclpy node (``dxboard_learn``, in a context of its own, spun by an
executor in a thread) that, every ``GRAPH_PERIOD_S``, reads the ROS 2 graph (the nodes, what each
publishes and subscribes, and whether it offers ``change_state``, the lifecycle service that makes
it a managed node) and subscribes to every topic it has not yet (raw: nothing is deserialised;
reliable where every publisher is, else best effort, which matches both). Each message's arrival
is noted on the monotonic clock, with its header's stamp when its type has one (read from the
bytes: the publisher's clock, free of this process's scheduling), under a lock (``probe`` reads the
counts while a channel is off: ``count`` counts by the stamps where there are some). ``close()``
stops the thread and the context; it is idempotent.
"""

from __future__ import annotations

import threading
import time
from typing import Any

from host.learn.infer import IGNORED
from host.learn.recording import NodeSeen, Recording
from host.observers.sources.ros2_message import RosMessage

NODE_NAME = "dxboard_learn"
GRAPH_PERIOD_S = 1.0
LIFECYCLE_SERVICE = "lifecycle_msgs/srv/ChangeState"
RECENT = 200  # messages that set the stamp clock's offset


class RosWatcher:
    def __init__(self, rec: Recording, domain: int | None = None) -> None:
        import rclpy
        from rclpy.context import Context
        from rclpy.executors import SingleThreadedExecutor
        from rclpy.node import Node
        from rclpy.signals import SignalHandlerOptions

        self.rec = rec
        self.lock = threading.Lock()
        self.context = Context()
        kw: dict[str, Any] = {} if domain is None else {"domain_id": domain}
        rclpy.init(context=self.context, signal_handler_options=SignalHandlerOptions.NO, **kw)
        self.node = Node(NODE_NAME, context=self.context)
        self.executor = SingleThreadedExecutor(context=self.context)
        self.executor.add_node(self.node)
        self._subs: dict[str, Any] = {}
        self._closed = False
        self.node.create_timer(GRAPH_PERIOD_S, self.read_graph)
        self.thread = threading.Thread(target=self._spin, name="learn-ros2", daemon=True)
        self.thread.start()

    def _spin(self) -> None:
        from rclpy.executors import ExternalShutdownException

        try:
            self.executor.spin()
        except ExternalShutdownException:
            pass
        except Exception:  # rclpy's executor racing its own shutdown: only then is it fine
            if not self._closed:
                raise

    def read_graph(self) -> None:
        """Note every node and its topics; subscribe to every new topic."""
        from host.observers.sources.ros2_convert import message_type

        node = self.node
        for name, ns in node.get_node_names_and_namespaces():
            if name == NODE_NAME or name.startswith("_"):
                continue
            try:
                pubs = node.get_publisher_names_and_types_by_node(name, ns)
                subs = node.get_subscriber_names_and_types_by_node(name, ns)
                srvs = node.get_service_names_and_types_by_node(name, ns)
            except Exception:  # the node left between the two calls
                continue
            managed = any(LIFECYCLE_SERVICE in types for _, types in srvs)
            with self.lock:
                old = self.rec.nodes.get(name, NodeSeen(name))
                self.rec.nodes[name] = NodeSeen(
                    name, tuple(dict.fromkeys((*old.publishes, *(t for t, _ in pubs)))),
                    tuple(dict.fromkeys((*old.subscribes, *(t for t, _ in subs)))),
                    old.managed or managed)
        for topic, types in node.get_topic_names_and_types():
            if topic in self._subs or IGNORED.search(topic) or not types:
                continue
            try:
                cls = message_type(types[0])
            except Exception:  # a type this machine cannot import
                self._subs[topic] = None
                continue
            with self.lock:
                self.rec.types[topic] = types[0]
            self._subs[topic] = node.create_subscription(
                cls, topic, self._on(topic, types[0]), self._qos(topic), raw=True)

    def _qos(self, topic: str) -> Any:
        """Reliable when every publisher is (a large message, a map, loses a fragment best
        effort on a busy machine, and then all of it); else best effort, which matches
        both kinds."""
        from rclpy.qos import QoSProfile, ReliabilityPolicy, qos_profile_sensor_data

        pubs = self.node.get_publishers_info_by_topic(topic)
        if pubs and all(p.qos_profile.reliability == ReliabilityPolicy.RELIABLE for p in pubs):
            return QoSProfile(depth=10, reliability=ReliabilityPolicy.RELIABLE)
        return qos_profile_sensor_data

    def _on(self, topic: str, type_name: str) -> Any:
        def on(raw: bytes) -> None:
            now = time.monotonic()
            stamp = RosMessage(now, topic, raw, type_name).stamp  # read from the CDR bytes
            with self.lock:
                self.rec.add(topic, now, stamp=stamp or None)
        return on

    def count(self, topic: str, since: float) -> int:
        """Messages of ``topic`` sent at ``since`` or later (``Recording.sent_since``)."""
        with self.lock:
            return self.rec.sent_since(topic, since, RECENT)

    def present(self) -> set[str]:
        """The nodes in the graph now."""
        return {n for n, _ in self.node.get_node_names_and_namespaces()}

    def close(self) -> None:
        if self._closed:
            return
        self._closed = True
        self.executor.shutdown(timeout_sec=5.0)
        self.thread.join(timeout=10.0)  # the spin has stopped before the node goes
        self.node.destroy_node()
        self.context.try_shutdown()
