"""The board link: connection, greeting, request and reply, and keeping the link honest.

Theory of operation. ``BoardLink(url, key)`` opens the transport, checks the HELLO (protocol
version, board id, boot id) and starts one reader task that owns every byte from the board (it
pumps the transport, which hands it messages in batches): a reply completes its request
(``host.board.requests``); a MEASUREMENT (or each reading of a MEASUREMENT_BATCH) and an EVENT
go to the ``Fanout`` (``host.board.fanout``), which hands them to every subscriber, unless the
channel count disagrees with the HELLO (dropped with a warning); an unexpected HELLO starts a
new session.

The link is *lost* when

- the transport says so (the stream ended, a write failed: the reader gets ``BoardUnreachable``);
- nothing new arrives for ``silence_limit`` seconds while subscribed (a frozen link, a board
  held in reset or hung): the silence rule of ``host.board.silence``, judged only after the
  host has read what already arrived;
- a keepalive PING (every ``keepalive_s`` while up, PROTOCOL.md §3) gets no answer within the
  request timeout: the only judge while nothing is subscribed;
- this host fails to read what arrived (a bug of its own): logged with its traceback, never
  a reader that ends quietly and leaves the link up and silent for good.

A lost link fails the pending requests (``LinkLost``), tells every subscriber (``LinkDown``)
and, with ``reconnect``, reopens the transport after the waits of the one reconnect policy
(``host.board.backoff.Backoff``: jittered, doubling, capped; a new one for every loss, so a
good connection resets it). While it is down, requests fail at once: nothing is sent to a
board that is not heard.

A new session (after a reconnect, or an unexpected HELLO: the board rebooted under a link that
stayed open) is finished beside the reader: the subscription is restored and the session waits
until the board is heard running (two measurements with different uptimes; the silence rule
ends a session that never gets there). Then a new boot id, or an uptime lower than the one seen
before plus the time away, is a reboot (``Rebooted``, published first), and the link is up:
``LinkUp``, requests allowed. Unsubscribed, the uptime comes from a STATE instead.
``clock`` must be the event loop's clock (its timeouts and backoff sleeps use it).
"""

from __future__ import annotations

import asyncio
import contextlib
import logging
import random
from collections.abc import Callable, Coroutine
from typing import Any

from host.board.backoff import Backoff
from host.board.fanout import Fanout
from host.board.requests import Requests
from host.board.silence import Silence
from host.board.types import BoardEvent, BoardInfo, LinkDown, LinkUp, Rebooted
from host.errors import RemoteError
from host.transports.base import BOOT_ID, Transport
from host.transports.errors import (
    BoardRefused,
    BoardUnreachable,
    LinkLost,
    NotSupported,
    RequestTimeout,
    VersionMismatch,
)
from protocol.constants import BOARD_CHANNEL, CAP_BATCH, PROTOCOL_VERSION
from protocol.framing import BadFrame
from protocol.messages import (
    Event,
    GetState,
    Hello,
    Measurement,
    MeasurementBatch,
    Message,
    Ping,
    Pong,
    State,
    Subscribe,
)

log = logging.getLogger(__name__)

KEEPALIVE_S = 10.0  # PING period while connected (the board closes silent sessions at 30 s)
UPTIME_SLACK_MS = 500  # uptime may lag the host's clock by this much (+5 %) without a reboot
DEFAULT_HOLD_MS = 30  # by default a reading waits on the board at most this long for its frame
MAX_PER_FRAME = 10  # SUBSCRIBE's per_frame 1-10 (PROTOCOL.md §4.2)


def default_per_frame(rate_hz: int) -> int:
    """Readings a frame asked by default at ``rate_hz``: as many as are sampled within
    ``DEFAULT_HOLD_MS`` (the first of a frame waits for the other k - 1), at least 1."""
    return max(1, min(MAX_PER_FRAME, 1 + rate_hz * DEFAULT_HOLD_MS // 1000))


class BoardLink:
    """See the module docstring. The board client (``host.board.client``) holds one."""

    def __init__(self, url: str, key: bytes | None, *, timeout_s: float,
                 connect_timeout_s: float, reconnect: bool, backoff_s: float,
                 max_backoff_s: float, silence_s: float | None, keepalive_s: float,
                 transport_factory: Callable[[str, bytes | None], Transport],
                 rng: random.Random | None, clock: Callable[[], float],
                 wall: Callable[[], float]) -> None:
        self.url = url
        self.key = key
        self.timeout_s = timeout_s
        self.connect_timeout_s = connect_timeout_s
        self.reconnect = reconnect
        self.backoff_s = backoff_s
        self.max_backoff_s = max_backoff_s
        self.keepalive_s = keepalive_s
        self.clock = clock
        self.wall = wall
        self._factory = transport_factory
        self._rng = rng or random.Random()
        self.transport: Transport = transport_factory(url, key)  # BadUrl at once
        self.fanout = Fanout(url)
        self.info: BoardInfo | None = None
        self.reboots = 0
        self.down_reason = ""  # why the link is down ("" while up)
        self.requests = Requests(url, timeout_s)
        self._reader: asyncio.Task[None] | None = None
        self._tasks: set[asyncio.Task[None]] = set()
        self._up = asyncio.Event()
        self._closing = False
        self._seen_uptime = (0, 0.0)  # (uptime ms, host monotonic s) last seen
        self._session = 0  # counts sessions (HELLOs accepted)
        self._losing = False  # the reader is handling a lost link
        self._seen_before = (0, 0.0)  # the (uptime, time) last seen before this session
        self.silence = Silence(clock, silence_s, keepalive_s, timeout_s,
                               lambda: self.transport.MAX_PUSH_HZ)
        self._down_since = 0.0

    # --- connection -----------------------------------------------------------------------

    @property
    def connected(self) -> bool:
        return self._up.is_set()

    async def open(self) -> BoardInfo:
        """Open the link and check the HELLO; ``BoardUnreachable`` or ``VersionMismatch``."""
        self._closing = False
        hello = await self.transport.open(self.connect_timeout_s)
        info = self._accept_hello(hello)
        self._reader = asyncio.create_task(self._read_loop(), name=f"board-reader {self.url}")
        self._up.set()
        self.down_reason = ""
        for guard, name in ((self._keepalive, "keepalive"), (self._watch_silence, "silence")):
            if not any(t.get_name() == name for t in self._tasks):
                self._spawn(guard(), name=name)
        return info

    async def close(self) -> None:
        """Stop the reader and the guards, close the transport, fail what is pending."""
        self._closing = True
        self._up.clear()
        reader, self._reader = self._reader, None
        if reader is not None:
            reader.cancel()
            with contextlib.suppress(asyncio.CancelledError):
                await reader
        for task in list(self._tasks):
            task.cancel()
        await self.transport.close()
        self.requests.fail_all(LinkLost(f"{self.url}: client closed", ""))

    def _accept_hello(self, hello: Hello) -> BoardInfo:
        if hello.version != PROTOCOL_VERSION:
            raise VersionMismatch(
                f"{self.url}: board speaks protocol version {hello.version}, "
                f"this host version {PROTOCOL_VERSION}",
                "flash matching firmware (dxboard flash) or use a matching dxboard")
        old = self.info
        self.info = BoardInfo(
            url=self.url, scheme=self.transport.SCHEME, version=hello.version,
            board_id=hello.board_id, firmware=hello.firmware, channels=hello.channels,
            capabilities=hello.capabilities, boot_id=hello.boot_id,
            reset_cause=hello.reset_cause, config_status=hello.config_status,
            transport_caps=self.transport.caps)
        self.fanout.new_session()
        self._new_session()
        if old is not None and old.board_id != hello.board_id:
            log.warning("%s: now board %r (was %r)", self.url, hello.board_id, old.board_id)
        return self.info

    def _spawn(self, coro: Coroutine[Any, Any, None], name: str | None = None) -> None:
        task = asyncio.get_running_loop().create_task(coro, name=name)
        self._tasks.add(task)
        task.add_done_callback(self._tasks.discard)

    # --- reading --------------------------------------------------------------------------

    async def _read_loop(self, lost: str | None = None,
                         after: asyncio.Task[None] | None = None) -> None:
        """Read and dispatch until closed; a lost link (``lost``, or the transport's word) is
        handled first. ``after``: the reader this one replaces (it is let finish first)."""
        if after is not None:
            await asyncio.wait([after])
        while True:
            if lost is not None:
                if not await self._link_lost(lost):
                    return
                lost = None
            try:
                await self.transport.pump(self._dispatch_all)
            except RemoteError as exc:  # any failure of the link is a lost link
                if self._closing:
                    return
                lost = str(exc)
            except Exception as exc:  # so is a failure of this host's own reading of it:
                # the reader must not end quietly (the silence rule judges only while a
                # reader runs, so the subscription would wait forever); said, and reconnected
                if self._closing:
                    return
                log.error("%s: reading the board's messages failed", self.url, exc_info=True)
                lost = f"the host failed reading the board's messages: {exc!r}"

    def _dispatch_all(self, batch: list[Message | BadFrame]) -> None:
        for msg in batch:
            self._dispatch(msg)

    def _dispatch(self, msg: Message | BadFrame) -> None:
        if isinstance(msg, BadFrame):
            log.warning("%s: bad frame from the board: %s", self.url, msg.text)
            return
        if self.requests.deliver(msg):
            return
        now = self.wall()
        info = self.info
        boot = info.boot_id if info else 0
        channels = info.channels if info else 0
        if isinstance(msg, Measurement):
            self._readings([msg], now, boot, channels)
        elif isinstance(msg, MeasurementBatch):
            self._readings(msg.readings, now, boot, channels)
        elif isinstance(msg, Event):
            if msg.channel >= channels and msg.channel != BOARD_CHANNEL:
                log.warning("%s: an event for channel %d of a board of %d: dropped", self.url,
                            msg.channel, channels)
                return
            self.fanout.publish(BoardEvent(now, boot, msg.seq, msg.uptime_ms, msg.kind,
                                           msg.channel, msg.old_state, msg.new_state,
                                           msg.faults, msg.value_ma, msg.dropped))
        elif isinstance(msg, Hello):
            if msg.req_id and self.info is not None and msg.boot_id == self.info.boot_id:
                # the answer to the transport's HELLO_REQUEST, after the board's own greeting:
                # the same session with a fresh nonce (the transport's codec signs with it)
                log.debug("%s: a second HELLO of this session: fresh nonce", self.url)
                return
            self._new_hello(msg)
        else:
            log.debug("%s: unsolicited %r dropped", self.url, msg)

    def _readings(self, batch: list[Measurement], now: float, boot: int, channels: int) -> None:
        """Readings that arrived together: news for the silence rule, then to the fan-out."""
        if len(batch[0].currents_ma) != channels:
            log.warning("%s: a measurement of %d channels from a board of %d: dropped",
                        self.url, len(batch[0].currents_ma), channels)
            return
        mono = self.clock()
        last = batch[-1].uptime_ms
        if len(batch) > 1:
            self.silence.news(batch[0].uptime_ms, mono)
        self.silence.news(last, mono)
        self.fanout.readings(batch, now, mono, boot, self.silence.rate)
        self._seen_uptime = (last, mono)

    def note_uptime(self, uptime_ms: int) -> None:
        """The board's uptime as a reply (PONG, STATE) told it, seen now."""
        self._seen_uptime = (uptime_ms, self.clock())

    # --- requests -------------------------------------------------------------------------

    async def _request_now(self, msg: Message) -> Message:
        """Send ``msg`` on the current link and wait for its reply (no waiting for a link)."""
        return await self.requests.send(self.transport, msg)

    async def request(self, msg: Message) -> Message:
        """Send a host message and return the board's reply; at once ``BoardUnreachable`` while
        the link is down."""
        if not self._up.is_set():
            if self._closing or self._reader is None:
                raise LinkLost(f"{self.url}: not connected", "connect first")
            raise BoardUnreachable(
                f"{self.url}: the link to the board is down ({self.down_reason}); "
                f"{type(msg).__name__} was not sent",
                "it reconnects by itself; check the board's power and the link")
        return await self._request_now(msg)

    async def expect(self, msg: Message, kind: type[Any]) -> Any:
        """``request`` whose reply must be a ``kind`` (else ``BoardRefused``)."""
        reply = await self.request(msg)
        if not isinstance(reply, kind):
            raise BoardRefused(f"{self.url}: expected {kind.__name__}, got {type(reply).__name__}",
                               "the board's firmware may not match this host")
        return reply

    async def ping(self, token: int = 0) -> int:
        """The board's uptime in ms (a round trip; also feeds the board's dead-man)."""
        pong: Pong = await self.expect(Ping(token), Pong)
        self.note_uptime(pong.uptime_ms)
        return pong.uptime_ms

    # --- the subscription -----------------------------------------------------------------

    def subscription(self, rate_hz: int) -> Subscribe:
        """The SUBSCRIBE for ``rate_hz``: with ``per_frame`` where the board can batch."""
        info = self.info
        if not rate_hz or info is None or not info.capabilities & CAP_BATCH:
            return Subscribe(rate_hz)
        return Subscribe(rate_hz, self.transport.per_frame or default_per_frame(rate_hz))

    @property
    def rate_hz(self) -> int:
        """The subscribed rate (0: nothing subscribed)."""
        return self.silence.rate

    @property
    def per_frame(self) -> int:
        """Readings a frame the board was asked for (1 when not batching)."""
        return self.silence.per_frame

    def subscribed(self, rate_hz: int, per_frame: int = 1) -> None:
        """The subscription's rate changed: the silence rule starts from now."""
        self.silence.subscribed(rate_hz, per_frame)

    async def _resubscribe(self) -> None:
        ask = self.subscription(self.silence.rate)
        try:
            await self._request_now(ask)
            self.silence.per_frame = ask.per_frame
        except (BoardUnreachable, BoardRefused) as exc:
            log.warning("%s: resubscribing failed: %s", self.url, exc)

    # --- the rules ----------------------------------------------------------------------

    @property
    def silence_limit(self) -> float | None:
        """Seconds without news after which a subscribed link is lost (``host.board.silence``);
        None while nothing is subscribed (the keepalive watches)."""
        return self.silence.limit()

    def _new_session(self) -> None:
        """A HELLO was accepted: a new session starts, heard from just now."""
        self._session += 1
        self._losing = False
        self._seen_before = self._seen_uptime
        self.silence.new_session()

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
        """The silence rule's watch: judging while the reader runs and no loss is handled."""
        def judging() -> bool:
            reader = self._reader
            return not self._losing and reader is not None and not reader.done()

        await self.silence.watch(judging, self._declare_lost, lambda: self._closing)

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
        self.requests.fail_all(LinkLost(f"{self.url}: link lost: {reason}",
                                    "the board may have rebooted or been unplugged"))
        self.fanout.publish(LinkDown(self.wall(), reason))
        await self.transport.close()
        if not self.reconnect:
            return False
        backoff = Backoff(self.backoff_s, self.max_backoff_s, rng=self._rng)
        while not self._closing:
            await asyncio.sleep(backoff.next())
            self.transport = self._factory(self.url, self.key)
            try:
                hello = await self.transport.open(self.connect_timeout_s)
                old = self._accept_new_hello(hello)
            except VersionMismatch as exc:
                log.error("%s", exc)
                self.fanout.publish(LinkDown(self.wall(), str(exc)))
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
        self.requests.fail_all(LinkLost(f"{self.url}: the board started a new session",
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
        session, heard = self._session, self.silence.heard
        if self.silence_limit is not None:
            await self._resubscribe()
            await heard.wait()  # a silent session is ended by the silence rule, which wakes us
        if session != self._session or self._closing:
            return
        rebooted = None
        if old is not None and old.boot_id != hello.boot_id:
            rebooted = Rebooted(self.wall(), old.boot_id, hello.boot_id, hello.reset_cause,
                                "boot id")
        elif old is not None and BOOT_ID not in self.transport.caps:
            # the same boot id of the board's own is the same boot, however far its uptime
            # fell behind (an emulator that stalled lets its clock slip)
            rebooted = await self._check_uptime(old, hello)
        if session != self._session or self._closing:
            return  # lost again meanwhile: the next session tells
        if rebooted is not None:
            self.reboots += 1
            log.warning("%s: board rebooted (%s changed, reset cause %s)", self.url,
                        rebooted.how, rebooted.reset_cause_name)
            self.fanout.publish(rebooted)
        self._up.set()
        self.down_reason = ""
        if self.info is not None:
            self.fanout.publish(LinkUp(self.wall(), down_s, self.info))

    async def _check_uptime(self, old: BoardInfo, hello: Hello) -> Rebooted | None:
        """A reboot the boot id does not show (boards that report none): the uptime now is
        lower than the one seen before plus the time in between."""
        seen_ms, seen_at = self._seen_before
        if not seen_at:
            return None
        if self.silence.last_uptime is None:  # not subscribed: ask
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
