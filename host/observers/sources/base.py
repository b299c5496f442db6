"""The topic-source interface: subscribe a topic name, get ``TopicMessage`` callbacks.

A source owns its clock (``clock``, seconds, monotonic by default): it stamps each message
with the host time it arrived, since it is the I/O edge; observers below it never read a clock.
Callbacks run on the asyncio loop's thread (a backend with its own threads marshals them
there through one ``host.observers.sources.inbox.Inbox``: one wakeup of the loop per batch,
never one per message, and ``dropped`` counts what a lagging loop lost), must not block, and
see messages of one topic in arrival order. ``waiting_since()`` is when the oldest message
still waiting in that inbox arrived (None: none waits): the loop is that far behind its
messages, and nothing may be judged silent ahead of it (``host.observers.hub``). ``close()`` is
idempotent; sources are async context managers.
"""

from __future__ import annotations

import asyncio
import time
from abc import ABC, abstractmethod
from collections.abc import Callable
from types import TracebackType

from host.observers.payload import TopicMessage
from host.observers.sources.inbox import Inbox

Callback = Callable[[TopicMessage], None]
Clock = Callable[[], float]


class Subscription(ABC):
    @abstractmethod
    def close(self) -> None:
        """Stop the callbacks (idempotent)."""


class TopicSource(ABC):
    def __init__(self, clock: Clock = time.monotonic) -> None:
        self.clock = clock
        self._closed = False
        self._inbox: Inbox[tuple[Callback, TopicMessage]] | None = None

    def _post(self, loop: asyncio.AbstractEventLoop, callback: Callback, msg: TopicMessage) -> None:
        """Hand ``callback(msg)`` to ``loop`` from a middleware thread (batched, bounded)."""
        inbox = self._inbox
        if inbox is None:
            inbox = self._inbox = Inbox(loop, _call, name=f"{type(self).__name__} messages")
        inbox.put((callback, msg))

    def waiting_since(self) -> float | None:
        """When the oldest message not yet handed to its callback arrived (the source's
        clock); None when none waits (or the source calls its subscribers at once)."""
        inbox = self._inbox
        item = None if inbox is None else inbox.oldest()
        return None if item is None else item[1].time

    @property
    def dropped(self) -> int:
        """Messages lost because the loop fell too far behind (see ``Inbox``)."""
        return 0 if self._inbox is None else self._inbox.dropped

    @abstractmethod
    def subscribe(self, topic: str, callback: Callback) -> Subscription:
        """Deliver every later message of ``topic`` (a name such as ``/odom``)."""

    def close(self) -> None:
        if not self._closed:
            self._closed = True
            self._close()

    def _close(self) -> None:  # noqa: B027 - a hook; most backends need no clean-up
        """Backend clean-up (called once)."""

    async def __aenter__(self) -> TopicSource:
        return self

    async def __aexit__(self, exc_type: type[BaseException] | None,
                        exc: BaseException | None, tb: TracebackType | None) -> None:
        self.close()


def _call(item: tuple[Callback, TopicMessage]) -> None:
    item[0](item[1])


def check_topic(topic: str) -> str:
    """``/odom`` style names: a leading slash, non-empty parts, no wildcards."""
    parts = topic.split("/")
    if not topic.startswith("/") or any(not p for p in parts[1:]) or any(
            c in topic for c in "*$?#"):
        raise ValueError(f"topic {topic!r} is not a name like /odom or /laser/scan")
    return topic
