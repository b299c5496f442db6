"""Handing messages from middleware threads to the asyncio loop: one wakeup per batch.

Zenoh and rclpy call their subscribers on threads of their own. Handing each message to the
loop with ``loop.call_soon_threadsafe`` writes one byte per message into the loop's self-pipe,
and asyncio's signal handling (``add_signal_handler``) shares that pipe: with the loop held up
for 2 s and messages arriving at 300 a second the pipe filled, the kernel refused the byte that
carries a signal's number, and SIGINT and SIGTERM were lost (issue 25, item 1).

``Inbox(loop, deliver)`` is the one hand-over point instead. ``put(item)`` on any thread
appends to a bounded ``collections.deque`` and schedules a single drain on the loop only when
none is pending, so a batch of any size costs one wakeup; the drain runs on the loop's thread
and calls ``deliver(item)`` for every item in arrival order (per topic, as the sources
promise). When the loop lags so far that ``maxlen`` items are held, the *oldest* is dropped
(fresh data matters more to a diagnosis than stale data), ``dropped`` counts every loss, and the
drain says so on the log, at most once every ``TELL_EVERY_S``, with the running total.

A drain delivers for at most ``SLICE_S`` and leaves the rest (ahead of newer items) to a drain
it schedules after whatever else the loop has ready: a loop that fell far behind (a recorder
starved at a load of 24, writing every message into its bag) held a stop request behind one
drain of thousands of messages, and did not react to SIGINT for a minute. So the loop's timers
run between slices while older items still wait: ``oldest()`` is the item waiting longest
(None: none waits), for a consumer that must not judge ahead of what it has not read yet (the
daemon's observer hub does not call a topic silent while its messages wait here).
"""

from __future__ import annotations

import asyncio
import collections
import logging
import threading
import time
from collections.abc import Callable
from typing import Generic, TypeVar

log = logging.getLogger(__name__)

T = TypeVar("T")

MAXLEN = 10_000  # items held while the loop lags: 5 s of a 2,000 msg/s flood
TELL_EVERY_S = 10.0
SLICE_S = 0.05  # a drain delivers this long at most, then lets the loop's other work run


class Inbox(Generic[T]):
    def __init__(self, loop: asyncio.AbstractEventLoop, deliver: Callable[[T], None],
                 maxlen: int = MAXLEN, name: str = "messages") -> None:
        self.loop = loop
        self.deliver = deliver
        self.maxlen = maxlen
        self.name = name
        self.dropped = 0  # items lost to a full inbox, since the start
        self.wakeups = 0  # drains scheduled (a batch each)
        self._items: collections.deque[T] = collections.deque(maxlen=maxlen)
        self._lock = threading.Lock()
        self._scheduled = False
        self._told = 0  # ``dropped`` when it was last said
        self._told_at = -TELL_EVERY_S

    def put(self, item: T) -> None:
        """Hand ``item`` to the loop (any thread; never blocks, never raises)."""
        with self._lock:
            if len(self._items) == self.maxlen:
                self.dropped += 1  # the deque drops the oldest as this one goes in
            self._items.append(item)
            if self._scheduled:
                return
            self._scheduled = True
            self.wakeups += 1
        try:
            self.loop.call_soon_threadsafe(self._drain)
        except RuntimeError:  # the loop closed while the middleware was still delivering
            with self._lock:
                self._scheduled = False

    def oldest(self) -> T | None:
        """The item waiting longest for a drain (any thread); None when none waits."""
        with self._lock:
            return self._items[0] if self._items else None

    def _drain(self) -> None:
        with self._lock:
            items = list(self._items)
            self._items.clear()
            self._scheduled = False
            dropped = self.dropped
        end = time.monotonic() + SLICE_S
        for i, item in enumerate(items):
            try:
                self.deliver(item)
            except Exception:  # one bad callback must not lose the rest of the batch
                log.exception("%s: delivering a message failed", self.name)
            if i + 1 < len(items) and time.monotonic() >= end:
                self._later(items[i + 1:])
                break
        if dropped != self._told and time.monotonic() - self._told_at >= TELL_EVERY_S:
            log.warning("%s: %d dropped so far (the event loop fell behind by more than %d; "
                        "the oldest go first)", self.name, dropped, self.maxlen)
            self._told, self._told_at = dropped, time.monotonic()

    def _later(self, rest: list[T]) -> None:
        """Put ``rest`` back ahead of what came in meanwhile (the oldest dropped if that is
        more than ``maxlen``), and drain it after the loop's other ready work."""
        with self._lock:
            merged = rest + list(self._items)
            over = len(merged) - self.maxlen
            if over > 0:
                self.dropped += over
                merged = merged[over:]
            self._items.clear()
            self._items.extend(merged)
            if self._scheduled:  # a put() meanwhile scheduled the next drain already
                return
            self._scheduled = True
            self.wakeups += 1
        self.loop.call_soon(self._drain)
