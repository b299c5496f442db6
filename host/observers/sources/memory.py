"""The in-process topic source: ``publish`` calls the subscribers at once, on the same thread.

For fast tests and for publishers living inside the daemon. ``publish(topic, payload, time)``
takes the time explicitly (or reads the source's clock), so tests can drive it on a simulated
clock; a payload may be bytes or a mapping (encoded with ``payload.encode``).
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

from host.observers.payload import TopicMessage, encode
from host.observers.sources.base import Callback, Subscription, TopicSource, check_topic


class _MemorySubscription(Subscription):
    def __init__(self, source: MemorySource, topic: str, callback: Callback) -> None:
        self._source = source
        self.topic = topic
        self.callback = callback

    def close(self) -> None:
        subs = self._source._subs.get(self.topic, [])
        if self in subs:
            subs.remove(self)


class MemorySource(TopicSource):
    def __init__(self, **kwargs: Any) -> None:
        super().__init__(**kwargs)
        self._subs: dict[str, list[_MemorySubscription]] = {}

    def subscribe(self, topic: str, callback: Callback) -> Subscription:
        sub = _MemorySubscription(self, check_topic(topic), callback)
        self._subs.setdefault(topic, []).append(sub)
        return sub

    def publish(self, topic: str, payload: bytes | Mapping[str, Any] = b"",
                time: float | None = None) -> TopicMessage:
        data = payload if isinstance(payload, bytes) else encode(payload)
        msg = TopicMessage(self.clock() if time is None else time, topic, data)
        for sub in list(self._subs.get(topic, ())):
            sub.callback(msg)
        return msg

    def _close(self) -> None:
        self._subs.clear()
