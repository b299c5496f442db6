"""When a ROS 2 recorder may say it records: its subscriptions matched with the graph's publishers.

A subscription made on a DDS topic receives nothing until discovery has matched it with each
publisher (SEDP: a fraction of a second on an idle host, seconds on a busy one), and the ROS 2
source makes it only once the topic's type is known (from the model, or from the graph). A
recorder that says "recording" before that misses what is published meanwhile: the start of a
fault injected right after the line. ``unmatched(source, subs)`` names the topics not yet
matched with every publisher the graph shows (a topic nobody publishes counts as unmatched
when it is ``required``: the graph may not be discovered yet); ``wait_matched`` polls it until
none is left, ``wait_s`` passes or ``stop`` is set, and returns what is still unmatched.
"""

from __future__ import annotations

import asyncio
import time
from collections.abc import Collection, Mapping

from host.observers.sources.base import Subscription
from host.observers.sources.ros2 import Ros2Source

POLL_S = 0.05


def unmatched(source: Ros2Source, subs: Mapping[str, Subscription],
              required: Collection[str]) -> list[str]:
    """The topics of ``subs`` not matched with all their publishers yet (sorted)."""
    node = source.ros.node
    out = []
    for topic, sub in sorted(subs.items()):
        reader = getattr(sub, "sub", None)  # the rclpy subscription, once the type is known
        publishers = node.count_publishers(topic)
        if publishers == 0:
            if topic in required:
                out.append(topic)
        elif not reader or reader.get_publisher_count() < publishers:
            out.append(topic)
    return out


async def wait_matched(source: Ros2Source, subs: Mapping[str, Subscription],
                       required: Collection[str], wait_s: float,
                       stop: asyncio.Event | None = None) -> list[str]:
    """Wait until every topic is matched (or ``wait_s``, or ``stop``); what is not, sorted."""
    end = time.monotonic() + wait_s
    while True:
        left = unmatched(source, subs, required)
        if not left or time.monotonic() >= end or (stop is not None and stop.is_set()):
            return left
        await asyncio.sleep(POLL_S)
