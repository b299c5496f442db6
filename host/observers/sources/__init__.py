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

from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from host.observers.sources.base import Callback, Subscription, TopicSource
    from host.observers.sources.memory import MemorySource

# loaded on first use (PEP 562): ros2_graph, a module of this package that the observers'
# section reads, needs none of them (nor asyncio, which they bring)
_HOMES = {"Callback": "host.observers.sources.base",
          "MemorySource": "host.observers.sources.memory",
          "Subscription": "host.observers.sources.base",
          "TopicSource": "host.observers.sources.base"}


def __getattr__(name: str) -> Any:
    import importlib

    if name in _HOMES:
        return getattr(importlib.import_module(_HOMES[name]), name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


__all__ = ["Callback", "MemorySource", "Subscription", "TopicSource"]
