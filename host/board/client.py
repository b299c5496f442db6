"""The async board client: one board, any transport, reconnecting, every reply checked.

Theory of operation. ``BoardClient(url, key)`` is composed of parts it holds, each an object
with a small interface of its own, none reaching into another's state:

- ``link`` (``host.board.link.BoardLink``): the connection, the HELLO, request and reply, the
  reader, and keeping the link honest (keepalive, silence, loss, reconnection with the one
  reconnect policy of ``host.board.backoff``, reboot detection); its ``fanout``
  (``host.board.fanout``) hands every reading, event and link notice to the subscribers;
- ``channels`` (``host.board.channels.ChannelNames``): channels by number or by name;
- ``actuator`` (``host.board.actuate.BoardActuator``): switch, power-cycle, clear, each read
  back and checked (a board that acknowledges "on" but reads the switch back off raises
  ``ReadbackMismatch``);
- ``configurator`` (``host.board.configure.BoardConfigurator``): channel and board
  configuration, read back and checked, and saving it.

The client itself reads the board (``state``, ``ping``), subscribes (``subscribe``: readings at
a rate, every event and link notice, until closed) and keeps thin delegates for actuation
(``switch``, ``power_cycle``, ``clear``), which the repair actuators, the daemon, the commands
and the benchmarks call all the time; configuration, which one command and the learning
session use, is reached as ``client.configurator``.

Readings a frame. A board with capability ``batch`` is asked (SUBSCRIBE's ``per_frame``) to
send its readings k at a time: the URL's ``per_frame=K`` if it says, else ``default_per_frame``
of the rate (readings held on the board at most ``DEFAULT_HOLD_MS``: k = 4 at 100 Hz, 1 below
34 Hz); a board without it, and every translating transport, is asked nothing new. Each reading
of a batch is stamped with the time it was sampled (``host.board.fanout``). EVENTs are never
held by the board.

While the link is down a request fails at once (``BoardUnreachable``): nothing is sent to a
board that is not heard. What the board says is checked against its HELLO: a STATE whose
channels are not the HELLO's ``0..n-1`` raises ``BadReply``. Capabilities the transport lacks
(``Transport.CAPS``) raise ``NotSupported`` before anything is sent.

Time is passed in: ``clock`` (monotonic seconds: readings' ``host_mono``, uptime checks, time
away) must be the event loop's clock, which its timeouts and backoff sleeps use
(``time.monotonic``, the default, is what asyncio's loop uses); ``wall`` stamps the
``host_time`` of everything it hands out. A test runs it on a simulated loop clock.
"""

from __future__ import annotations

import contextlib
import random
import time
from collections.abc import AsyncIterator, Callable

from host.board.actuate import BoardActuator
from host.board.channels import ChannelNames
from host.board.configure import BoardConfigurator
from host.board.link import KEEPALIVE_S, BoardLink
from host.board.types import BoardInfo, BoardState, ChannelState, Reading, StreamItem, SwitchResult
from host.transports import open_transport
from host.transports.base import Transport
from host.transports.errors import BadReply, BadRequest, BoardRefused, BoardUnreachable
from protocol.messages import Ack, GetState, Message, State, Subscribe


class BoardClient:
    """See the module docstring. Use as ``async with BoardClient(url, key) as board:``."""

    def __init__(self, url: str, key: bytes | None = None, *, timeout_s: float = 2.0,
                 connect_timeout_s: float = 5.0, reconnect: bool = True,
                 backoff_s: float = 0.1, max_backoff_s: float = 5.0,
                 silence_s: float | None = None, keepalive_s: float = KEEPALIVE_S,
                 transport_factory: Callable[[str, bytes | None], Transport] = open_transport,
                 rng: random.Random | None = None,
                 clock: Callable[[], float] = time.monotonic,
                 wall: Callable[[], float] = time.time) -> None:
        self.link = BoardLink(
            url, key, timeout_s=timeout_s, connect_timeout_s=connect_timeout_s,
            reconnect=reconnect, backoff_s=backoff_s, max_backoff_s=max_backoff_s,
            silence_s=silence_s, keepalive_s=keepalive_s, transport_factory=transport_factory,
            rng=rng, clock=clock, wall=wall)
        self.channels = ChannelNames(self.link)
        self.actuator = BoardActuator(self.link, self.channels)
        self.configurator = BoardConfigurator(self.link, self.channels)

    # --- what the link knows ----------------------------------------------------------

    @property
    def url(self) -> str:
        return self.link.url

    @property
    def key(self) -> bytes | None:
        return self.link.key

    @property
    def timeout_s(self) -> float:
        return self.link.timeout_s

    @property
    def transport(self) -> Transport:
        """The transport of the current session (a new one after every reconnect)."""
        return self.link.transport

    @property
    def info(self) -> BoardInfo | None:
        """The board as its last HELLO described it (None before the first)."""
        return self.link.info

    @property
    def latest(self) -> Reading | None:
        return self.link.fanout.latest

    @property
    def reboots(self) -> int:
        return self.link.reboots

    @property
    def connected(self) -> bool:
        return self.link.connected

    @property
    def down_reason(self) -> str:
        return self.link.down_reason

    @property
    def silence_limit(self) -> float | None:
        return self.link.silence_limit

    @property
    def per_frame(self) -> int:
        """Readings a frame the board was asked for (1 when not batching)."""
        return self.link.per_frame

    def clock(self) -> float:
        return self.link.clock()

    # --- connection -------------------------------------------------------------------

    async def __aenter__(self) -> BoardClient:
        await self.connect()
        return self

    async def __aexit__(self, *exc: object) -> None:
        await self.close()

    async def connect(self) -> BoardInfo:
        """Open the link and check the HELLO; ``BoardUnreachable`` or ``VersionMismatch``."""
        return await self.link.open()

    async def close(self) -> None:
        """Stop the reader, unsubscribe nobody (the link closes), close the transport."""
        await self.link.close()

    async def request(self, msg: Message) -> Message:
        """Send a host message and return the board's reply (``BoardUnreachable`` at once while
        the link is down)."""
        return await self.link.request(msg)

    # --- reading ----------------------------------------------------------------------

    async def ping(self, token: int = 0) -> int:
        """The board's uptime in ms (a round trip; also feeds the board's dead-man)."""
        return await self.link.ping(token)

    async def state(self) -> BoardState:
        st: State = await self.link.expect(GetState(), State)
        info = self.info
        n = info.channels if info else len(st.channels)
        ids = [c.channel for c in st.channels]
        if ids != list(range(n)):
            raise BadReply(f"{self.url}: the board's STATE lists channels {ids}, but its HELLO "
                           f"announced {n} channels (0..{n - 1})",
                           "a corrupted or lying reply: nothing was believed from it; if it "
                           "persists, the firmware may not match this host")
        self.link.note_uptime(st.uptime_ms)
        names = await self.channels.names()
        chans = tuple(
            ChannelState(c.channel, names[c.channel] if c.channel < len(names) else "",
                         c.commanded, c.physical, c.state, c.current_ma, c.live_faults,
                         c.sticky_faults, c.trips, c.retries)
            for c in st.channels)
        boot = info.boot_id if info else 0
        return BoardState(self.link.wall(), boot, st.uptime_ms, st.input_mv, st.total_ma,
                          st.reset_cause, st.config_status, st.board_flags, chans)

    async def channel_names(self) -> list[str]:
        """Channel names from the board's configuration ("ch<N>" where it cannot say)."""
        return await self.channels.names()

    async def channel(self, ch: int | str) -> int:
        """The channel number for a number or a name; ``BadChannel`` if there is none."""
        return await self.channels.number(ch)

    def is_stale(self, max_age_s: float) -> bool:
        """True when there is no reading newer than ``max_age_s`` seconds (or the link is down)."""
        latest = self.latest
        return latest is None or not self.connected or latest.stale(max_age_s, self.clock())

    async def subscribe(self, rate_hz: int = 10) -> AsyncIterator[StreamItem]:
        """Readings at ``rate_hz`` (1-100) and every event and link notice, until closed.
        Over transports without push the transport polls at that rate."""
        if not 1 <= rate_hz <= 100:
            raise BadRequest(f"rate {rate_hz} Hz is out of range", "use 1..100 Hz")
        link = self.link
        sub = link.fanout.add()
        try:
            if rate_hz > link.rate_hz:
                ask = link.subscription(rate_hz)
                await link.expect(ask, Ack)
                link.subscribed(rate_hz, ask.per_frame)
            while True:
                yield await sub.get()
        finally:
            link.fanout.remove(sub)
            if not link.fanout.subs and link.rate_hz and link.connected:
                link.subscribed(0)
                with contextlib.suppress(BoardUnreachable, BoardRefused):
                    await link.expect(Subscribe(0), Ack)

    # --- actuation (thin delegates to ``actuator``: the calls every caller makes) ----------

    async def switch(self, ch: int | str, on: bool, force: bool = False) -> SwitchResult:
        """Switch a channel; the read-back must show the switch where it was asked to be."""
        return await self.actuator.switch(ch, on, force)

    async def power_cycle(self, ch: int | str, off_s: float = 1.0,
                          force: bool = False) -> SwitchResult:
        """Switch off, wait ``off_s``, switch on (the board times it where it can)."""
        return await self.actuator.power_cycle(ch, off_s, force)

    async def clear(self, ch: int | str) -> SwitchResult | None:
        """Clear a channel's latch and sticky faults (``"all"``: every channel)."""
        return await self.actuator.clear(ch)
