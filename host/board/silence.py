"""The silence rule of the board link: how long a subscribed board may say nothing new.

``Silence`` is the part of the board link (``host.board.link``) that judges a subscribed link by
what arrives on it. Only news counts: a measurement whose uptime differs from the one before
(a board whose clock stands still, held in reset or its main loop hung while something still
answers, is no sign of life). The limit is ``silence_s`` if given, else ``SILENCE_PERIODS``
periods of the subscription (plus the k - 1 periods a board batching k readings a frame waits
between frames; at most the transport's ``MAX_PUSH_HZ`` a second), at least ``SILENCE_MIN_S``
and at most one keepalive period plus the request timeout (the keepalive would tell by then);
None while nothing is subscribed. ``watch`` calls the link's ``lost`` once a limit passed, but
only after the host has read what already arrived: a host that stalled is not a silent board.
It also tells when a session's board was first heard running (``heard``: two measurements
with different uptimes). The link passes every fact in; the rule reads only ``clock``.
"""

from __future__ import annotations

import asyncio
import contextlib
from collections.abc import Callable

SILENCE_PERIODS = 10  # subscription periods without a message that make a link lost...
SILENCE_MIN_S = 0.5  # ...but never less than this
SILENCE_TOLERANCE_S = 0.001  # a silence this close to its limit has reached it (float residue)


class Silence:
    """See the module docstring."""

    def __init__(self, clock: Callable[[], float], silence_s: float | None, keepalive_s: float,
                 timeout_s: float, max_push_hz: Callable[[], float | None]) -> None:
        self.clock = clock
        self.silence_s = silence_s  # None: derived from the subscription rate
        self.keepalive_s = keepalive_s
        self.timeout_s = timeout_s
        self._max_push_hz = max_push_hz  # the most a transport hands out a second (None: no bound)
        self.rate = 0  # the subscribed rate (0: nothing subscribed)
        self.per_frame = 1  # readings a frame the board was asked for
        self.last_rx = 0.0  # host monotonic time of the last news from the board
        self.last_uptime: int | None = None  # of this session's last measurement
        self.heard = asyncio.Event()  # this session's board was heard running
        self._rearm = asyncio.Event()  # the rule changed (a session, a subscription)

    def limit(self) -> float | None:
        """Seconds without news after which a subscribed link is lost; None while nothing is
        subscribed (the keepalive watches)."""
        if not self.rate:
            return None
        if self.silence_s is not None:
            return self.silence_s
        most = self._max_push_hz()
        rate = min(self.rate, most) if most else self.rate
        # a board sending k readings a frame is silent k - 1 periods between frames
        derived = max(SILENCE_MIN_S, (SILENCE_PERIODS + self.per_frame - 1) / rate)
        return min(derived, self.keepalive_s + self.timeout_s)

    def new_session(self) -> None:
        """A HELLO was accepted: a new session, heard from just now, not yet heard running."""
        self.last_rx = self.clock()
        self.last_uptime = None
        self.heard.set()  # wakes the last session's waiter: it sees that it is over
        self.heard = asyncio.Event()
        self._rearm.set()

    def subscribed(self, rate_hz: int, per_frame: int = 1) -> None:
        """The subscription's rate changed: the rule starts from now."""
        self.rate = rate_hz
        self.per_frame = per_frame
        self.last_rx = self.clock()
        self._rearm.set()

    def news(self, uptime_ms: int, now: float) -> None:
        """A measurement arrived at ``now`` (the host's clock): news if the board's clock moved
        since the last one."""
        last, self.last_uptime = self.last_uptime, uptime_ms
        if last is None or uptime_ms != last:
            self.last_rx = now
        if last is not None and uptime_ms != last and not self.heard.is_set():
            self.heard.set()

    async def watch(self, judging: Callable[[], bool], lost: Callable[[str], None],
                    closing: Callable[[], bool]) -> None:
        """Until ``closing()``: ``lost(reason)`` when no news arrived within the limit while
        ``judging()`` (the link's reader runs and no loss is being handled)."""
        while not closing():
            limit = self.limit()
            self._rearm.clear()
            if limit is None or not judging():
                await self._rearm.wait()
                continue
            wait = self.last_rx + limit - self.clock()
            if wait > SILENCE_TOLERANCE_S:
                with contextlib.suppress(TimeoutError):
                    await asyncio.wait_for(self._rearm.wait(), wait)
                continue
            await asyncio.sleep(0)  # read what arrived first: a stalled host is no silent board
            limit = self.limit()
            if limit is not None and self.last_rx + limit - self.clock() <= SILENCE_TOLERANCE_S:
                lost(f"nothing from the board for {limit:g} s")
