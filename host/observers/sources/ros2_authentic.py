"""Authentic ROS 2 topics: a message counts only if the model's node for its topic published it.

Any participant of a DDS domain may publish any topic, so a stranger's ``/odom`` at 300 Hz
would look like a base that races and a stranger's ``/scan`` would hide a hung lidar. The
model says which component publishes which topic (``publishes:`` in ``system.yaml``), and a
component's name is its ROS 2 node's name. ``Publishers(node, topic, allowed, tell)`` checks
each message of one topic by the endpoint that published it: rclpy hands a subscription
callback the message's info with ``publisher_gid``, and the graph
(``get_publishers_info_by_topic``) names the node of each endpoint gid. ``admit(info)`` is
True for an endpoint of an allowed node; an endpoint of another node is refused and told
once per node (``tell(topic, node)``); an endpoint the graph does not show yet, or shows
without its node (``_NODE_NAME_UNKNOWN_``: DDS discovery and ROS's node information arrive
apart, and both may lag the first messages), is refused without a word until it does, the
graph being read again at most every ``LOOKUP_S``. A middleware that gives no gid cannot be
checked: its messages are admitted. This checks names, not identities: a stranger that
names its node like the model's publisher passes; a domain that must resist that needs
SROS2 (docs/security.md).
"""

from __future__ import annotations

import time
from collections.abc import Callable, Collection, Mapping
from typing import Any

LOOKUP_S = 0.2  # the least time between two readings of the graph for an unknown endpoint
UNKNOWN = "_NODE_NAME_UNKNOWN_"  # the graph's name of an endpoint whose node it has not seen


class Publishers:
    def __init__(self, node: Any, topic: str, allowed: Collection[str],
                 tell: Callable[[str, str], None]) -> None:
        self.node = node  # the rclpy node whose graph names the endpoints
        self.topic = topic
        self.allowed = frozenset(allowed)
        self.tell = tell
        self.known: dict[bytes, str] = {}  # endpoint gid -> node name
        self.told: set[str] = set()
        self.refused = 0
        self._looked = float("-inf")

    def admit(self, info: Mapping[str, Any]) -> bool:
        """Whether the message with this ``MessageInfo`` comes from an allowed node."""
        gid = info.get("publisher_gid")
        if not gid:
            return True
        key = bytes(gid["data"])
        name = self.known.get(key)
        if name is None:
            now = time.monotonic()
            if now - self._looked >= LOOKUP_S:
                self._looked = now
                for e in self.node.get_publishers_info_by_topic(self.topic):
                    if e.node_name != UNKNOWN:
                        self.known[bytes(e.endpoint_gid)] = e.node_name
                name = self.known.get(key)
        if name in self.allowed:
            return True
        self.refused += 1
        if name is not None and name not in self.told:
            self.told.add(name)
            self.tell(self.topic, name)
        return False
