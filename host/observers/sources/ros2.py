"""The ROS 2 topic source: the robot's topics over DDS through rclpy, counted without decoding.

``Ros2Source(domain_id)`` is one rclpy node (``dxboard_observer``) in a thread of its own
(``ros2_node`` beside it). ``subscribe("/scan", cb)`` needs the topic's type: given in ``types``
(``{"/scan": "sensor_msgs/msg/LaserScan"}``), or else learnt from the ROS 2 graph, which
the source reads every ``discovery_s`` until a publisher of the topic shows up (so the
observers may start before the robot's nodes). Subscriptions are *raw*: rclpy hands over the
serialized CDR bytes, stamped with the source's clock on the executor's thread and passed to
the asyncio loop through the source's inbox (one wakeup per batch, ``TopicSource._post``) as a
``ros2_message.RosMessage``. A
frequency observer only counts them; value and diagnostic observers decode them on demand.

QoS adapts to the publishers, as ``ros2 bag record`` does: keep last ``DEPTH``, reliable when every
publisher of the topic the graph shows is reliable (a large message, such as a 4 MB map, is
then never lost to a dropped fragment), best effort otherwise (which matches any publisher);
a topic subscribed through ``types`` before its publishers are known gets best effort.
``DEPTH`` is 100, not ROS's usual 10: the reader holds what arrives while the executor is
held up (a daemon descheduled on a busy machine), a second of a 100 Hz topic; with 10 a stall
of 0.1 s dropped messages, which the frequency observer took for a rate drop. The messages
stay serialized in DDS's history and take memory only while the executor lags. ``depths``
(topic -> depth) gives a topic more (a recorder's ``/board_stream``: every item counts).

A subscription's callback takes every message already queued for it (up to ``DRAIN``) before
it returns. rclpy's executor rebuilds its wait set in Python for each message it hands over
(about 0.4 ms of CPU), so a topic whose messages queue up costs a wait per message. A
stranger's ``/odom`` at 300 Hz on a loaded machine then kept the executor so busy that every
other topic fell silent for 2-5 s (issue 25: 2 of 3 runs repaired a healthy robot, 0 of 3
without the stranger). Taken at once, a queued message costs a ``take`` alone, and the
executor gets back to the other topics.

``GRAPH`` (``/_graph/nodes``) is not a DDS topic: subscribing it delivers, every
``discovery_s``, a message whose values are ``{"nodes": [names...]}`` from the ROS 2 graph,
for ``host.observers.sources.ros2_graph.GraphObserver`` (node presence). Nor is
``/_lifecycle/NODE`` (``ros2_lifecycle.LIFECYCLE``): subscribing it asks ``/NODE/get_state``
every ``discovery_s`` (one call at a time; a node that does not answer gets no message, so
its observer's literal expires) and delivers ``{"state": LABEL}``, or ``{"state": "absent"}``
while the node is not in the graph, for ``ros2_lifecycle.LifecycleObserver``.

``publishers`` (topic -> the model's node names) makes the topics authentic
(``ros2_authentic``): a message of such a topic from another node's endpoint is not
delivered, and ``on_stranger(topic, node)`` (set by the daemon; called on the loop) is told
once per topic and node. A topic without an entry takes every publisher (a bag's player).
"""

from __future__ import annotations

import asyncio
import logging
from collections.abc import Callable, Collection, Mapping
from typing import Any

from rclpy.exceptions import InvalidHandle
from rclpy.qos import QoSHistoryPolicy, QoSProfile, QoSReliabilityPolicy

from host.observers.payload import TopicMessage, encode
from host.observers.sources.base import Callback, Subscription, TopicSource, check_topic
from host.observers.sources.ros2_authentic import Publishers
from host.observers.sources.ros2_convert import message_type
from host.observers.sources.ros2_graph import GRAPH
from host.observers.sources.ros2_lifecycle import ABSENT, LIFECYCLE
from host.observers.sources.ros2_message import RosMessage
from host.observers.sources.ros2_node import RosNode

log = logging.getLogger(__name__)

STATE_CALL_S = 10.0  # a get_state call unanswered this long is asked again
DEPTH = 100  # messages kept per topic while the executor lags (see the module docstring)
DRAIN = DEPTH  # messages taken at once after the one the executor hands over
BEST_EFFORT = QoSProfile(history=QoSHistoryPolicy.KEEP_LAST, depth=DEPTH,
                         reliability=QoSReliabilityPolicy.BEST_EFFORT)
RELIABLE = QoSProfile(history=QoSHistoryPolicy.KEEP_LAST, depth=DEPTH,
                      reliability=QoSReliabilityPolicy.RELIABLE)


class _RosSubscription(Subscription):
    def __init__(self, source: Ros2Source, topic: str, callback: Callback,
                 loop: asyncio.AbstractEventLoop) -> None:
        self.source = source
        self.topic = topic
        self.callback = callback
        self.loop = loop
        self.sub: Any = None  # the rclpy subscription once the type is known
        self.open = True

    def deliver(self, msg: TopicMessage) -> None:  # on the executor's thread
        if self.open:
            self.source._post(self.loop, self.callback, msg)

    def close(self) -> None:
        if self.open:
            self.open = False
            self.source._drop(self)


class Ros2Source(TopicSource):
    def __init__(self, domain_id: int | None = None, types: Mapping[str, str] | None = None,
                 discovery_s: float = 0.5, name: str = "dxboard_observer",
                 publishers: Mapping[str, Collection[str]] | None = None,
                 depths: Mapping[str, int] | None = None, **kwargs: Any) -> None:
        super().__init__(**kwargs)
        self.types = dict(types or {})
        self.depths = dict(depths or {})
        self.publishers = {t: frozenset(n) for t, n in (publishers or {}).items()}
        self.on_stranger: Callable[[str, str], None] | None = None
        self.ros = RosNode(name, domain_id)
        self._subs: list[_RosSubscription] = []
        self._state_clients: dict[str, Any] = {}  # node -> its get_state client
        self._asking: dict[str, float] = {}  # node -> when its get_state call was made
        self._timer = self.ros.node.create_timer(discovery_s, self._discover)

    def subscribe(self, topic: str, callback: Callback) -> Subscription:
        sub = _RosSubscription(self, check_topic(topic), callback, asyncio.get_running_loop())
        self._subs.append(sub)
        if topic != GRAPH and not topic.startswith(LIFECYCLE) and topic in self.types:
            self._attach(sub, self.types[topic])
        return sub

    def nodes(self) -> list[str]:
        """The nodes in the ROS 2 graph now (names, without namespaces)."""
        return sorted({n for n, _ in self.ros.node.get_node_names_and_namespaces()})

    def _discover(self) -> None:  # on the executor's thread, every discovery_s
        graph = None
        for sub in list(self._subs):
            if sub.topic == GRAPH:
                sub.deliver(TopicMessage(self.clock(), GRAPH, encode({"nodes": self.nodes()})))
            elif sub.topic.startswith(LIFECYCLE):
                self._ask_state(sub)
            elif sub.sub is None:
                if graph is None:
                    graph = dict(self.ros.node.get_topic_names_and_types())
                found = graph.get(sub.topic)
                if found:
                    self._attach(sub, found[0])

    def _ask_state(self, sub: _RosSubscription) -> None:
        """Ask the node of a ``/_lifecycle/NODE`` subscription its state (executor thread)."""
        from lifecycle_msgs.srv import GetState

        node = sub.topic[len(LIFECYCLE):]
        asked = self._asking.get(node)
        if asked is not None and self.clock() - asked < STATE_CALL_S:
            return  # the last call is still under way: a busy or hung node
        if node not in self.nodes():
            sub.deliver(TopicMessage(self.clock(), sub.topic, encode({"state": ABSENT})))
            return
        client = self._state_clients.get(node)
        if client is None:
            client = self._state_clients[node] = self.ros.node.create_client(
                GetState, f"/{node}/get_state")
        if not client.service_is_ready():
            return  # in the graph, its service not discovered yet
        self._asking[node] = self.clock()
        future = client.call_async(GetState.Request())

        def done(f: Any) -> None:
            self._asking.pop(node, None)
            result = f.result() if not f.cancelled() and f.exception() is None else None
            if result is not None:
                state = str(result.current_state.label)
                sub.deliver(TopicMessage(self.clock(), sub.topic, encode({"state": state})))

        future.add_done_callback(done)

    def _attach(self, sub: _RosSubscription, type_name: str) -> None:
        try:
            msg_type = message_type(type_name)
        except TypeError as exc:
            log.error("%s: %s; not observed", sub.topic, exc)
            sub.sub = False
            return
        clock, topic = self.clock, sub.topic
        allowed = self.publishers.get(topic)
        check = None if allowed is None else Publishers(
            self.ros.node, topic, allowed, lambda t, n: self._stranger(sub.loop, t, n))

        def one(data: bytes, info: Mapping[str, Any]) -> None:
            if check is None or check.admit(info):
                sub.deliver(RosMessage(clock(), topic, data, type_name))

        def on_raw(data: bytes, info: Mapping[str, Any]) -> None:  # on the executor's thread
            one(data, info)
            handle = getattr(sub.sub, "handle", None)
            for _ in range(DRAIN):  # what else is queued now, without a wait each (see above)
                if handle is None:
                    return
                try:
                    with handle:
                        got = handle.take_message(msg_type, True)
                except InvalidHandle:  # destroyed meanwhile: the subscription was dropped
                    return
                if got is None:
                    return
                one(got[0], got[1])

        pubs = self.ros.node.get_publishers_info_by_topic(topic)
        reliable = bool(pubs) and all(
            p.qos_profile.reliability == QoSReliabilityPolicy.RELIABLE for p in pubs)
        qos = RELIABLE if reliable else BEST_EFFORT
        depth = self.depths.get(topic)
        if depth is not None:
            qos = QoSProfile(history=QoSHistoryPolicy.KEEP_LAST, depth=depth,
                             reliability=qos.reliability)
        sub.sub = self.ros.node.create_subscription(msg_type, topic, on_raw, qos, raw=True)
        log.info("observing %s (%s, %s)", topic, type_name,
                 "reliable" if reliable else "best effort")

    def _stranger(self, loop: asyncio.AbstractEventLoop, topic: str, node: str) -> None:
        """Tell of a stranger's endpoint (on the executor's thread; once per topic and node,
        so one wakeup of the loop each is no flood)."""
        log.warning("%s: ignoring messages of node %s, which the model does not say "
                    "publishes it", topic, node)
        if self.on_stranger is not None and not loop.is_closed():
            loop.call_soon_threadsafe(self.on_stranger, topic, node)

    def _drop(self, sub: _RosSubscription) -> None:
        if sub in self._subs:
            self._subs.remove(sub)
        if sub.sub:
            self.ros.node.destroy_subscription(sub.sub)

    def _close(self) -> None:
        for sub in list(self._subs):
            sub.close()
        self.ros.close()
