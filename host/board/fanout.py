"""The board's items handed out to every subscriber: readings stamped, no loss silent.

``Fanout`` is the outgoing half of the board link (``host.board.link``): every item the link
hands out (a ``Reading``, a ``BoardEvent``, the link notices ``LinkDown``, ``LinkUp``,
``Rebooted``) is put to each ``Subscriber`` of it, in order. Readings that arrived together
(one MEASUREMENT, or a MEASUREMENT_BATCH's k, oldest first) are stamped with the time they were
sampled, not their arrival: the last gets the arrival time, each earlier one that minus the
difference of their uptimes (at most the batch's span at the subscribed rate: a board's uptime
cannot move the stamps further), never before a reading handed out earlier (batches read
together after a stall of the host). Within a session the board numbers measurements from 1,
so a gap becomes ``Reading.missed``. A subscriber that falls ``QUEUE_LIMIT`` items behind loses
the oldest, and the readings among them are added to ``missed`` of the next one it gets.
"""

from __future__ import annotations

import asyncio
import collections
import dataclasses
import logging

from host.board.types import Reading, StreamItem
from protocol.messages import Measurement

log = logging.getLogger(__name__)

QUEUE_LIMIT = 4096  # items a subscriber may fall behind before the oldest are dropped


class Subscriber:
    """One subscriber's items, in order: at most ``QUEUE_LIMIT``. When it falls behind, the
    oldest are dropped; the readings among them (and those they said were missed before them)
    are added to ``missed`` of the next reading it gets, so no loss is silent. A deque and one
    waiter, not an ``asyncio.Queue``: a hundred readings a second from each of several boards
    pass here."""

    def __init__(self, url: str) -> None:
        self.url = url
        self.items: collections.deque[StreamItem] = collections.deque()
        self.dropped = 0  # readings lost since the last one handed out
        self._waiter: asyncio.Future[None] | None = None

    def put(self, item: StreamItem) -> None:
        if len(self.items) >= QUEUE_LIMIT:
            old = self.items.popleft()
            if isinstance(old, Reading):
                self.dropped += 1 + old.missed
            else:
                log.warning("%s: a subscriber fell %d items behind: dropped %r", self.url,
                            QUEUE_LIMIT, old)
        self.items.append(item)
        waiter = self._waiter
        if waiter is not None and not waiter.done():
            waiter.set_result(None)

    async def get(self) -> StreamItem:
        while not self.items:
            self._waiter = asyncio.get_running_loop().create_future()
            try:
                await self._waiter
            finally:
                self._waiter = None
        item = self.items.popleft()
        if self.dropped and isinstance(item, Reading):
            item = dataclasses.replace(item, missed=item.missed + self.dropped)
            self.dropped = 0
        return item


class Fanout:
    """The subscribers of one board and the stamping of its readings; see the module
    docstring. It reads no clock: the link passes the times in."""

    def __init__(self, url: str) -> None:
        self.url = url
        self.subs: list[Subscriber] = []
        self.latest: Reading | None = None
        self._last_seq = 0  # of this session's last measurement (0: none yet)
        self._stamped = 0.0  # host monotonic time of the last reading handed out

    def add(self) -> Subscriber:
        sub = Subscriber(self.url)
        self.subs.append(sub)
        return sub

    def remove(self, sub: Subscriber) -> None:
        self.subs.remove(sub)

    def publish(self, item: StreamItem) -> None:
        for sub in self.subs:
            sub.put(item)

    def new_session(self) -> None:
        """The board numbers the measurements of a new session from 1 again."""
        self._last_seq = 0

    def readings(self, batch: list[Measurement], now: float, mono: float, boot: int,
                 rate_hz: int) -> None:
        """Hand out readings that arrived together at ``now`` (wall) and ``mono`` (monotonic),
        each stamped with when it was sampled (the module docstring's rule)."""
        last = batch[-1].uptime_ms
        span = len(batch) / rate_hz if rate_hz else 0.0
        floor = self._stamped
        subs = self.subs
        reading = None
        for msg in batch:
            at = mono
            if msg.uptime_ms != last:
                back = ((last - msg.uptime_ms) & 0xFFFFFFFF) / 1000
                at = mono - (back if back < span else span)
                if at < floor:
                    at = floor
            floor = at
            missed = msg.seq - self._last_seq - 1 if self._last_seq else 0
            self._last_seq = msg.seq
            reading = Reading(now - (mono - at), at, boot, msg.seq, msg.uptime_ms,
                              msg.input_mv, msg.on_mask, msg.fault_mask,
                              tuple(msg.currents_ma), missed if missed > 0 else 0)
            for sub in subs:
                sub.put(reading)
        self._stamped = floor
        self.latest = reading
