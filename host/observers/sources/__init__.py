"""Topic sources: where observers get topic messages from, behind one small interface.

``TopicSource.subscribe(topic, callback)`` delivers every message of ``topic`` as a ``Message``
(host receive time, topic, payload) to ``callback`` on the asyncio loop's thread; the returned
``Subscription`` is closed to stop. Backends: ``memory`` (in-process, synchronous, for fast
tests and for drivers living in the daemon) and ``zenoh`` (Eclipse Zenoh in peer mode, no
router: the default, and what ROS 2's rmw_zenoh runs on) and ``ros2`` (rclpy, with its thread
``ros2_node``, ``ros2_convert`` and ``ros2_message`` for messages and ``ros2_graph`` for node
presence). ``open_source(kind, ...)`` picks one; sources for other middlewares plug in the same
way.
"""

from __future__ import annotations

from host.observers.sources.base import Callback, Subscription, TopicSource
from host.observers.sources.memory import MemorySource

__all__ = ["Callback", "MemorySource", "Subscription", "TopicSource"]
