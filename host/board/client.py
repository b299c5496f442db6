"""The async board client: one board, any transport, reconnecting, every reply checked.

Theory of operation. ``BoardClient(url, key)`` opens the transport for the URL, checks the
HELLO (protocol version, board id, boot id) and starts one reader task that owns every byte
from the board (it pumps the transport: messages are handed to it in batches, from the
transport's data callback where it decodes there, so no task wakes per message): a reply is
matched to its request by ``req_id`` and completes that request's
future; a MEASUREMENT becomes a ``Reading`` and an EVENT a ``BoardEvent`` for every
subscriber; an unexpected HELLO starts a new session. Requests have a timeout
(``RequestTimeout``); an ERROR reply raises ``BoardRefused`` (``AuthRefused`` for a bad or
missing key) and changes nothing on the board. Actuation checks the read-back: a board that
acknowledges "on" but reads the switch back off raises ``ReadbackMismatch``.

Readings a frame. A board with capability ``batch`` is asked (SUBSCRIBE's ``per_frame``) to
send its readings k at a time: the URL's ``per_frame=K`` if it says, else ``default_per_frame``
of the rate (readings held on the board at most ``DEFAULT_HOLD_MS``: k = 4 at 100 Hz, 1 below
34 Hz); a board without it, and every translating transport, is asked nothing new. Each
reading of a MEASUREMENT_BATCH is handed out as a MEASUREMENT's would be, in order, and
stamped with the time it was sampled, not the batch's arrival: the last reading gets the
arrival time, each earlier one that minus the difference of their uptimes (``host_time`` and
``host_mono`` spaced as sampled, not k at one instant; never before a reading handed out
earlier). EVENTs are never held by the board.

Whether the link is alive is judged in ``host.board.link`` (``LinkMixin``): a link that ends, a
subscription that falls silent for ``silence_limit`` seconds or an unanswered keepalive PING is a
lost link (``LinkDown``, pending requests fail with ``LinkLost``); with ``reconnect=True`` the
client reconnects with backoff, reports a reboot (``Rebooted``), subscribes again at the same
rate and announces ``LinkUp`` once the board is heard again. While the link is down a request
fails at once (``BoardUnreachable``): nothing is sent to a board that is not heard. Within a
session the board numbers measurements from 1, so a gap becomes ``Reading.missed``; nothing is
lost without a trace. What the board says is checked against its HELLO: a STATE whose channels
are not the HELLO's ``0..n-1`` raises ``BadReply``; a measurement or event for a channel the
board does not have is dropped with a warning.

Capabilities the transport lacks (``Transport.CAPS``) raise ``NotSupported`` before anything
is sent. Channels are named by number or by name (names come from the board's configuration,
read once per connection where the transport can read it). Actuation with its read-back
checks is in ``host.board.actuate``, configuration in ``host.board.configure``.

Time is passed in: ``clock`` (monotonic seconds: readings' ``host_mono``, uptime checks, time
away) must be the event loop's clock, which its timeouts and backoff sleeps use
(``time.monotonic``, the default, is what asyncio's loop uses); ``wall`` stamps the
``host_time`` of everything it hands out. A test runs it on a simulated loop clock.
"""

from __future__ import annotations

import asyncio
import collections
import contextlib
import dataclasses
import logging
import random
import time
from collections.abc import AsyncIterator, Callable, Coroutine
from typing import Any

from host.board.actuate import ActuateMixin
from host.board.configure import ConfigMixin
from host.board.link import KEEPALIVE_S, LinkMixin
from host.board.types import (
    BoardEvent,
    BoardInfo,
    BoardState,
    ChannelState,
    Reading,
    StreamItem,
)
from host.errors import RemoteError
from host.transports import open_transport
from host.transports.base import CLIENT_MAX_REQ_ID, NAMES, Transport
from host.transports.errors import (
    AuthRefused,
    BadChannel,
    BadReply,
    BadRequest,
    BoardRefused,
    BoardUnreachable,
    LinkLost,
    NotSupported,
    RequestTimeout,
    VersionMismatch,
)
from protocol.constants import (
    BOARD_CHANNEL,
    CAP_BATCH,
    E_AUTH_REQUIRED,
    E_BAD_TAG,
    E_NO_SESSION,
    E_REPLAYED,
    ERROR_TEXT,
    PROTOCOL_VERSION,
)
from protocol.framing import BadFrame
from protocol.messages import (
    Ack,
    ChannelConfig,
    Error,
    Event,
    GetConfig,
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

AUTH_CODES = (E_AUTH_REQUIRED, E_BAD_TAG, E_REPLAYED, E_NO_SESSION)
QUEUE_LIMIT = 4096  # items a subscriber may fall behind before the oldest are dropped
DEFAULT_HOLD_MS = 30  # by default a reading waits on the board at most this long for its frame
MAX_PER_FRAME = 10  # SUBSCRIBE's per_frame 1-10 (PROTOCOL.md §4.2)


def default_per_frame(rate_hz: int) -> int:
    """Readings a frame asked by default at ``rate_hz``: as many as are sampled within
    ``DEFAULT_HOLD_MS`` (the first of a frame waits for the other k - 1), at least 1."""
    return max(1, min(MAX_PER_FRAME, 1 + rate_hz * DEFAULT_HOLD_MS // 1000))


class _Subscriber:
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


class BoardClient(LinkMixin, ActuateMixin, ConfigMixin):
    """See the module docstring. Use as ``async with BoardClient(url, key) as board:``."""

    def __init__(self, url: str, key: bytes | None = None, *, timeout_s: float = 2.0,
                 connect_timeout_s: float = 5.0, reconnect: bool = True,
                 backoff_s: float = 0.1, max_backoff_s: float = 5.0,
                 silence_s: float | None = None, keepalive_s: float = KEEPALIVE_S,
                 transport_factory: Callable[[str, bytes | None], Transport] = open_transport,
                 rng: random.Random | None = None,
                 clock: Callable[[], float] = time.monotonic,
                 wall: Callable[[], float] = time.time) -> None:
        self.url = url
        self.key = key
        self.timeout_s = timeout_s
        self.connect_timeout_s = connect_timeout_s
        self.reconnect = reconnect
        self.backoff_s = backoff_s
        self.max_backoff_s = max_backoff_s
        self.silence_s = silence_s  # None: derived from the subscription rate (LinkMixin)
        self.keepalive_s = keepalive_s
        self._factory = transport_factory
        self._rng = rng or random.Random()
        self.clock = clock  # the host's monotonic clock: Reading.host_mono, uptimes, backoff
        self.wall = wall  # the host's wall clock: the host_time of everything handed out
        self.transport: Transport = transport_factory(url, key)  # BadUrl at once
        self.info: BoardInfo | None = None
        self.latest: Reading | None = None
        self.reboots = 0
        self._pending: dict[int, asyncio.Future[Message]] = {}
        self._req = 0
        self._subs: list[_Subscriber] = []
        self._rate = 0
        self._names: list[str] | None = None
        self._reader: asyncio.Task[None] | None = None
        self._up = asyncio.Event()
        self._closing = False
        self._last_seq = 0
        self._seen_uptime = (0, 0.0)  # (uptime ms, host monotonic s) last seen
        self._stamped = 0.0  # host monotonic time of the last reading handed out
        self._tasks: set[asyncio.Task[None]] = set()
        self._link_init()

    # --- connection -------------------------------------------------------------------

    async def __aenter__(self) -> BoardClient:
        await self.connect()
        return self

    async def __aexit__(self, *exc: object) -> None:
        await self.close()

    async def connect(self) -> BoardInfo:
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
            transport_caps=self.transport.CAPS)
        self._last_seq = 0
        self._new_session()
        if old is not None and old.board_id != hello.board_id:
            log.warning("%s: now board %r (was %r)", self.url, hello.board_id, old.board_id)
            self._names = None
        return self.info

    async def close(self) -> None:
        """Stop the reader, unsubscribe nobody (the link closes), close the transport."""
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
        self._fail_pending(LinkLost(f"{self.url}: client closed", ""))

    @property
    def connected(self) -> bool:
        return self._up.is_set()

    def _fail_pending(self, exc: Exception) -> None:
        pending, self._pending = self._pending, {}
        for fut in pending.values():
            if not fut.done():
                fut.set_exception(exc)

    def _publish(self, item: StreamItem) -> None:
        for sub in self._subs:
            sub.put(item)

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

    def _dispatch_all(self, batch: list[Message | BadFrame]) -> None:
        for msg in batch:
            self._dispatch(msg)

    def _dispatch(self, msg: Message | BadFrame) -> None:
        if isinstance(msg, BadFrame):
            log.warning("%s: bad frame from the board: %s", self.url, msg.text)
            return
        fut = self._pending.pop(msg.req_id, None) if msg.req_id else None
        if fut is not None:
            if not fut.done():
                fut.set_result(msg)
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
            self._publish(BoardEvent(now, boot, msg.seq, msg.uptime_ms, msg.kind, msg.channel,
                                     msg.old_state, msg.new_state, msg.faults, msg.value_ma,
                                     msg.dropped))
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
        """Readings that arrived together (one, or a MEASUREMENT_BATCH's, oldest first), each
        stamped with when it was sampled: the arrival time less its uptime's distance to the
        last one's (at most the batch's span at the subscribed rate: a board's uptime cannot
        move the stamps further), never before a reading handed out earlier (batches read
        together after a stall of the host)."""
        if len(batch[0].currents_ma) != channels:
            log.warning("%s: a measurement of %d channels from a board of %d: dropped",
                        self.url, len(batch[0].currents_ma), channels)
            return
        mono = self.clock()
        last = batch[-1].uptime_ms
        if len(batch) > 1:
            self._news(batch[0].uptime_ms, mono)
        self._news(last, mono)
        span = len(batch) / self._rate if self._rate else 0.0
        floor = self._stamped
        subs = self._subs
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
        self._seen_uptime = (last, mono)
        self.latest = reading

    def _subscription(self, rate_hz: int) -> Subscribe:
        """The SUBSCRIBE for ``rate_hz``: with ``per_frame`` where the board can batch."""
        info = self.info
        if not rate_hz or info is None or not info.capabilities & CAP_BATCH:
            return Subscribe(rate_hz)
        return Subscribe(rate_hz, self.transport.per_frame or default_per_frame(rate_hz))

    @property
    def per_frame(self) -> int:
        """Readings a frame the board was asked for (1 when not batching)."""
        return self._per_frame

    def _note_uptime(self, uptime_ms: int) -> None:
        self._seen_uptime = (uptime_ms, self.clock())

    def _spawn(self, coro: Coroutine[Any, Any, None], name: str | None = None) -> None:
        task = asyncio.get_running_loop().create_task(coro, name=name)
        self._tasks.add(task)
        task.add_done_callback(self._tasks.discard)

    # --- requests ---------------------------------------------------------------------

    def _next_req(self) -> int:
        self._req = self._req % CLIENT_MAX_REQ_ID + 1  # the transports' own ids lie above
        return self._req

    async def _request_now(self, msg: Message) -> Message:
        """Send ``msg`` on the current link and wait for its reply (no waiting for a link)."""
        msg.req_id = self._next_req()
        fut: asyncio.Future[Message] = asyncio.get_running_loop().create_future()
        self._pending[msg.req_id] = fut
        name = type(msg).__name__
        try:
            await self.transport.send(msg)
            reply = await asyncio.wait_for(fut, self.timeout_s)
        except TimeoutError:
            raise RequestTimeout(
                f"{self.url}: the board did not answer {name} within {self.timeout_s:g} s",
                "the board stopped answering; check its power and the link") from None
        finally:
            self._pending.pop(msg.req_id, None)
        if isinstance(reply, Error):
            text = reply.text or ERROR_TEXT.get(reply.code, "error")
            if reply.code in AUTH_CODES:
                raise AuthRefused(f"{self.url}: the board refused {name}: {text}",
                                  "check the key (DXBOARD_KEY or --key-file); nothing changed",
                                  reply.code)
            raise BoardRefused(f"{self.url}: the board refused {name}: {text}",
                               "nothing was changed", reply.code)
        return reply

    async def request(self, msg: Message) -> Message:
        """Send a host message and return the board's reply (waiting for a link first)."""
        if not self._up.is_set():
            if self._closing or self._reader is None:
                raise LinkLost(f"{self.url}: not connected", "connect first")
            raise BoardUnreachable(
                f"{self.url}: the link to the board is down ({self.down_reason}); "
                f"{type(msg).__name__} was not sent",
                "it reconnects by itself; check the board's power and the link")
        return await self._request_now(msg)

    async def _expect(self, msg: Message, kind: type[Any]) -> Any:
        reply = await self.request(msg)
        if not isinstance(reply, kind):
            raise BoardRefused(f"{self.url}: expected {kind.__name__}, got {type(reply).__name__}",
                               "the board's firmware may not match this host")
        return reply

    def _need(self, cap: str, what: str) -> None:
        if cap not in self.transport.CAPS:
            raise NotSupported(f"{self.url}: {what} is not possible over {self.transport.SCHEME}",
                               "use the board's native transport (tcp:// or serial://)")

    # --- reading ----------------------------------------------------------------------

    async def ping(self, token: int = 0) -> int:
        """The board's uptime in ms (a round trip; also feeds the board's dead-man)."""
        pong: Pong = await self._expect(Ping(token), Pong)
        self._note_uptime(pong.uptime_ms)
        return pong.uptime_ms

    async def state(self) -> BoardState:
        st: State = await self._expect(GetState(), State)
        n = self.info.channels if self.info else len(st.channels)
        ids = [c.channel for c in st.channels]
        if ids != list(range(n)):
            raise BadReply(f"{self.url}: the board's STATE lists channels {ids}, but its HELLO "
                           f"announced {n} channels (0..{n - 1})",
                           "a corrupted or lying reply: nothing was believed from it; if it "
                           "persists, the firmware may not match this host")
        self._note_uptime(st.uptime_ms)
        names = await self.channel_names()
        chans = tuple(
            ChannelState(c.channel, names[c.channel] if c.channel < len(names) else "",
                         c.commanded, c.physical, c.state, c.current_ma, c.live_faults,
                         c.sticky_faults, c.trips, c.retries)
            for c in st.channels)
        boot = self.info.boot_id if self.info else 0
        return BoardState(self.wall(), boot, st.uptime_ms, st.input_mv, st.total_ma,
                          st.reset_cause, st.config_status, st.board_flags, chans)

    async def channel_names(self) -> list[str]:
        """Channel names from the board's configuration ("ch<N>" where it cannot say)."""
        if self._names is None:
            n = self.info.channels if self.info else 0
            names = [f"ch{i}" for i in range(n)]
            if NAMES in self.transport.CAPS:
                for i in range(n):
                    cfg: ChannelConfig = await self._expect(GetConfig(i), ChannelConfig)
                    names[i] = cfg.name or names[i]
            self._names = names
        return list(self._names)

    async def channel(self, ch: int | str) -> int:
        """The channel number for a number or a name; ``BadChannel`` if there is none."""
        names = await self.channel_names()
        text = str(ch).strip()
        if text.isdigit() and int(text) < len(names):
            return int(text)
        if text in names:
            return names.index(text)
        raise BadChannel(f"{self.url}: no channel {text!r}",
                         f"use 0..{len(names) - 1} or one of: {', '.join(names)}")

    def is_stale(self, max_age_s: float) -> bool:
        """True when there is no reading newer than ``max_age_s`` seconds (or the link is down)."""
        return self.latest is None or not self.connected or self.latest.stale(
            max_age_s, self.clock())

    async def subscribe(self, rate_hz: int = 10) -> AsyncIterator[StreamItem]:
        """Readings at ``rate_hz`` (1-100) and every event and link notice, until closed.
        Over transports without push the transport polls at that rate."""
        if not 1 <= rate_hz <= 100:
            raise BadRequest(f"rate {rate_hz} Hz is out of range", "use 1..100 Hz")
        sub = _Subscriber(self.url)
        self._subs.append(sub)
        try:
            if rate_hz > self._rate:
                ask = self._subscription(rate_hz)
                await self._expect(ask, Ack)
                self._subscribed(rate_hz, ask.per_frame)
            while True:
                yield await sub.get()
        finally:
            self._subs.remove(sub)
            if not self._subs and self._rate and self.connected:
                self._subscribed(0)
                with contextlib.suppress(BoardUnreachable, BoardRefused):
                    await self._expect(Subscribe(0), Ack)
