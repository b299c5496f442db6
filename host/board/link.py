"""Keeping the board link honest: keepalive, silence, loss, reconnection and reboots.

Theory of operation. ``LinkMixin`` is the half of ``BoardClient`` that judges whether the link
to the board is alive and brings it back. The link is *lost* when

- the transport says so (the stream ended, a write failed: the reader gets ``BoardUnreachable``);
- nothing arrives for ``silence_limit`` seconds while subscribed (a frozen link, a board held in
  reset or hung): ``silence_s`` if given, else ``SILENCE_PERIODS`` periods of the subscription
  (plus the k - 1 periods a board batching k readings a frame waits between frames), at least
  ``SILENCE_MIN_S`` and at most one keepalive period plus the request timeout (the
  keepalive would tell by then anyway);
- a keepalive PING (every ``keepalive_s`` while up, PROTOCOL.md §3) gets no answer within the
  request timeout: the only judge while nothing is subscribed.

Silence is judged only after the host has read what already arrived: a host that stalled (a busy
machine) is not a silent board. Only news counts: a measurement whose uptime repeats the one
before (a board whose clock stands still: held in reset, its main loop hung, while something
still answers) is no sign of life. A lost link fails the pending requests (``LinkLost``), tells
every subscriber (``LinkDown``) and, with ``reconnect``, reopens the transport with exponential
backoff and jitter (``backoff_s`` doubling up to ``max_backoff_s``, each wait drawn from [½, 1]
of it). While it is down, requests fail at once: nothing is sent to a board that is not heard.

A new session (after a reconnect, or an unexpected HELLO: the board rebooted under a link that
stayed open) is finished beside the reader: the subscription is restored and the session waits
until the board is heard running (two measurements with different uptimes; the silence rule
ends a session that never gets there). Then a new boot id, or an uptime lower than the one seen
before plus the time away, is a reboot (``Rebooted``, published first), and the link is up:
``LinkUp``, requests allowed. Unsubscribed, the uptime comes from a STATE instead.
"""

from __future__ import annotations

import asyncio
import contextlib
import logging
import random
from collections.abc import Callable, Coroutine
from typing import Any

from host.board.types import BoardInfo, LinkDown, LinkUp, Rebooted, StreamItem
from host.errors import RemoteError
from host.transports.base import Transport
from host.transports.errors import (
    BoardRefused,
    BoardUnreachable,
    LinkLost,
    NotSupported,
    RequestTimeout,
    VersionMismatch,
)
from protocol.messages import GetState, Hello, Message, State, Subscribe

log = logging.getLogger(__name__)

KEEPALIVE_S = 10.0  # PING period while connected (the board closes silent sessions at 30 s)
SILENCE_PERIODS = 10  # subscription periods without a message that make a link lost...
SILENCE_MIN_S = 0.5  # ...but never less than this
UPTIME_SLACK_MS = 500  # uptime may lag the host's clock by this much (+5 %) without a reboot
SILENCE_TOLERANCE_S = 0.001  # a silence this close to its limit has reached it (float residue)


class LinkMixin:
    """Needs the client's connection attributes (below) and ``_request_now``, ``ping``,
    ``_publish``, ``_fail_pending``, ``_accept_hello``, ``_read_loop`` and ``_spawn``."""

    url: str
    key: bytes | None
    timeout_s: float
    connect_timeout_s: float
    reconnect: bool
    backoff_s: float
    max_backoff_s: float
    keepalive_s: float
    silence_s: float | None
    clock: Callable[[], float]
    wall: Callable[[], float]
    transport: Transport
    info: BoardInfo | None
    reboots: int
    _factory: Callable[[str, bytes | None], Transport]
    _rng: random.Random
    _rate: int
    _reader: asyncio.Task[None] | None
    _up: asyncio.Event
    _closing: bool
    _seen_uptime: tuple[int, float]

    def _link_init(self) -> None:
        self._session = 0  # counts sessions (HELLOs accepted)
        self._losing = False  # the reader is handling a lost link
        self._last_rx = 0.0  # host monotonic time of the last news from the board
        self._last_uptime: int | None = None  # of this session's last measurement
        self._seen_before = (0, 0.0)  # the (uptime, time) last seen before this session
        self._heard = asyncio.Event()  # this session's board was heard running
        self._rearm = asyncio.Event()  # the silence rule changed (a session, a subscription)
        self._down_since = 0.0
        self._per_frame = 1  # readings a frame the board was asked for
        self.down_reason = ""  # why the link is down ("" while up)

    # --- the rules ----------------------------------------------------------------------

    @property
    def silence_limit(self) -> float | None:
        """Seconds without news from the board (a measurement with a new uptime) after which a
        subscribed link is lost; None while nothing is subscribed (the keepalive watches)."""
        if not self._rate:
            return None
        if self.silence_s is not None:
            return self.silence_s
        most = self.transport.MAX_PUSH_HZ
        rate = min(self._rate, most) if most else self._rate
        # a board sending k readings a frame is silent k - 1 periods between frames
        derived = max(SILENCE_MIN_S, (SILENCE_PERIODS + self._per_frame - 1) / rate)
        return min(derived, self.keepalive_s + self.timeout_s)

    def _new_session(self) -> None:
        """A HELLO was accepted: a new session starts, heard from just now."""
        self._session += 1
        self._losing = False
        self._last_rx = self.clock()
        self._last_uptime = None
        self._seen_before = self._seen_uptime
        self._heard.set()  # wakes the last session's waiter: it sees that it is over
        self._heard = asyncio.Event()
        self._rearm.set()

    def _news(self, uptime_ms: int, now: float) -> None:
        """A measurement arrived at ``now`` (the host's clock): news if the board's clock moved
        since the last one."""
        last, self._last_uptime = self._last_uptime, uptime_ms
        if last is None or uptime_ms != last:
            self._last_rx = now
        if last is not None and uptime_ms != last and not self._heard.is_set():
            self._heard.set()

    def _subscribed(self, rate_hz: int, per_frame: int = 1) -> None:
        """The subscription's rate changed: the silence rule starts from now."""
        self._rate = rate_hz
        self._per_frame = per_frame
        self._last_rx = self.clock()
        self._rearm.set()

    async def _keepalive(self) -> None:
        """PING every ``keepalive_s`` while up: a board closes a session that sent it nothing for
        30 s, and an unanswered PING is a lost link."""
        while not self._closing:
            await asyncio.sleep(self.keepalive_s)
            if not self._up.is_set():
                continue
            try:
                await self.ping()
            except NotSupported:
                return
            except RequestTimeout:
                self._declare_lost(f"no answer to a keepalive PING within {self.timeout_s:g} s")
            except (BoardUnreachable, BoardRefused) as exc:
                log.debug("%s: keepalive: %s", self.url, exc)  # the reader handles the link

    async def _watch_silence(self) -> None:
        """Declare the link lost when no news arrived for ``silence_limit`` while subscribed."""
        while not self._closing:
            limit = self.silence_limit
            self._rearm.clear()
            reader = self._reader
            if limit is None or self._losing or reader is None or reader.done():
                await self._rearm.wait()
                continue
            wait = self._last_rx + limit - self.clock()
            if wait > SILENCE_TOLERANCE_S:
                with contextlib.suppress(TimeoutError):
                    await asyncio.wait_for(self._rearm.wait(), wait)
                continue
            await asyncio.sleep(0)  # read what arrived first: a stalled host is no silent board
            limit = self.silence_limit
            if limit is not None and self._last_rx + limit - self.clock() <= SILENCE_TOLERANCE_S:
                self._declare_lost(f"nothing from the board for {limit:g} s")

    def _declare_lost(self, reason: str) -> None:
        """The link is lost though the transport did not say so: replace the reader by one that
        handles the loss first."""
        reader = self._reader
        if self._closing or self._losing or reader is None or reader.done():
            return
        self._losing = True
        self._up.clear()
        self._reader = asyncio.get_running_loop().create_task(
            self._read_loop(lost=reason, after=reader), name=f"board-reader {self.url}")
        reader.cancel()

    # --- losing and finding the link ------------------------------------------------------

    async def _link_lost(self, reason: str) -> bool:
        """Handle a lost link (in the reader); True when it is back (the reader goes on)."""
        self._losing = True
        self._up.clear()
        self._down_since = self.clock()
        self.down_reason = reason
        log.warning("%s: link lost: %s", self.url, reason)
        self._fail_pending(LinkLost(f"{self.url}: link lost: {reason}",
                                    "the board may have rebooted or been unplugged"))
        self._publish(LinkDown(self.wall(), reason))
        await self.transport.close()
        if not self.reconnect:
            return False
        delay = self.backoff_s
        while not self._closing:
            await asyncio.sleep(delay * (0.5 + 0.5 * self._rng.random()))
            delay = min(delay * 2, self.max_backoff_s)
            self.transport = self._factory(self.url, self.key)
            try:
                hello = await self.transport.open(self.connect_timeout_s)
                old = self._accept_new_hello(hello)
            except VersionMismatch as exc:
                log.error("%s", exc)
                self._publish(LinkDown(self.wall(), str(exc)))
                await self.transport.close()
                return False
            except RemoteError as exc:
                log.info("%s: reconnect failed: %s", self.url, exc)
                await self.transport.close()
                continue
            self._spawn(self._finish_session(old, hello, self.clock() - self._down_since))
            return True
        return False

    def _new_hello(self, hello: Hello) -> None:
        """An unexpected HELLO on an open link: the board started a new session (it rebooted).
        Requests in flight belong to the old one and get no answer: they fail now."""
        self._up.clear()
        self.down_reason = "the board started a new session"
        self._fail_pending(LinkLost(f"{self.url}: the board started a new session",
                                    "the board may have rebooted; try again"))
        try:
            old = self._accept_new_hello(hello)
        except VersionMismatch as exc:
            log.error("%s", exc)
            return
        self._spawn(self._finish_session(old, hello, 0.0))

    def _accept_new_hello(self, hello: Hello) -> BoardInfo | None:
        """The synchronous half of a new session: check the HELLO, keep the old info."""
        old = self.info
        self._accept_hello(hello)
        return old

    async def _finish_session(self, old: BoardInfo | None, hello: Hello, down_s: float) -> None:
        """The rest of a new session (beside the reader): resubscribe, hear the board running,
        tell a reboot, then up."""
        session, heard = self._session, self._heard
        if self.silence_limit is not None:
            await self._resubscribe()
            await heard.wait()  # a silent session is ended by the silence rule, which wakes us
        if session != self._session or self._closing:
            return
        rebooted = None
        if old is not None and old.boot_id != hello.boot_id:
            rebooted = Rebooted(self.wall(), old.boot_id, hello.boot_id, hello.reset_cause,
                                "boot id")
        elif old is not None:
            rebooted = await self._check_uptime(old, hello)
        if session != self._session or self._closing:
            return  # lost again meanwhile: the next session tells
        if rebooted is not None:
            self.reboots += 1
            log.warning("%s: board rebooted (%s changed, reset cause %s)", self.url,
                        rebooted.how, rebooted.reset_cause_name)
            self._publish(rebooted)
        self._up.set()
        self.down_reason = ""
        if self.info is not None:
            self._publish(LinkUp(self.wall(), down_s, self.info))

    async def _check_uptime(self, old: BoardInfo, hello: Hello) -> Rebooted | None:
        """A reboot the boot id does not show (boards that report none): the uptime now is
        lower than the one seen before plus the time in between."""
        seen_ms, seen_at = self._seen_before
        if not seen_at:
            return None
        if self._last_uptime is None:  # not subscribed: ask
            try:
                state = await self._request_now(GetState())
            except (BoardUnreachable, BoardRefused):
                return None
            if not isinstance(state, State):
                return None
            self._seen_uptime = (state.uptime_ms, self.clock())
        now_ms, now_at = self._seen_uptime
        away_ms = (now_at - seen_at) * 1000
        if now_ms + UPTIME_SLACK_MS + away_ms * 0.05 < seen_ms + away_ms:
            return Rebooted(self.wall(), old.boot_id, hello.boot_id, hello.reset_cause, "uptime")
        return None

    async def _resubscribe(self) -> None:
        ask = self._subscription(self._rate)
        try:
            await self._request_now(ask)
            self._per_frame = ask.per_frame
        except (BoardUnreachable, BoardRefused) as exc:
            log.warning("%s: resubscribing failed: %s", self.url, exc)

    # --- what the client provides -------------------------------------------------------

    async def _request_now(self, msg: Message) -> Message:
        raise NotImplementedError

    async def ping(self, token: int = 0) -> int:
        raise NotImplementedError

    def _subscription(self, rate_hz: int) -> Subscribe:
        raise NotImplementedError

    def _publish(self, item: StreamItem) -> None:
        raise NotImplementedError

    def _fail_pending(self, exc: Exception) -> None:
        raise NotImplementedError

    def _accept_hello(self, hello: Hello) -> BoardInfo:
        raise NotImplementedError

    async def _read_loop(self, lost: str | None = None,
                         after: asyncio.Task[None] | None = None) -> None:
        raise NotImplementedError

    def _spawn(self, coro: Coroutine[Any, Any, None], name: str | None = None) -> None:
        raise NotImplementedError
