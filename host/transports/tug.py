"""``tug://HOST:PORT``: the original TEDUSAR power board's format (``protocol/tug.py``) over TCP.

URL grammar: ``tug://HOST:PORT``, no query parameters. For the boards of the original project
as they are (their ``Board.cpp``) and for ours (``dxboard emulate --tug H:P``,
``firmware/tug.py``). The wire knows channels, currents, voltages and on/off, nothing else, so
this transport translates (``translate``):

- open: the board sends SPECIFICATIONS as a client connects; their count is the channel count
  (a board that sends none within ``SPECS_WAIT_S`` is asked a REQUEST, whose MEASUREMENTS
  count). The HELLO says board id ``tug@HOST:PORT``, boot id 0, no key.
- One command at a time, the next only once the board answered the last: the original board
  reads one command per ``recv`` and drops whatever else the chunk holds.
- GET_STATE and PING: REQUEST, answered by a one-byte ACK, then MEASUREMENTS (status 1 = on,
  anything else off; the wire has no faults, so none are reported).
- SWITCH: CHANNEL, then the ACK's error byte (0 done; else refused, ``protocol.tug.ACK_TEXT``),
  then REQUESTs until the status follows (``SETTLE_S``). The force flag cannot be expressed:
  our board never switches a protected channel off over tug. POWER_CYCLE is off, wait, on by
  the host.
- SUBSCRIBE: the first one sends SET FREQUENCY (the asked rate, at most 255), once per link:
  the original board starts another one-second broadcaster for every SET FREQUENCY and stops
  none, and both boards broadcast once a second whatever the rate. SUBSCRIBE 0 only stops
  the pushes. After SET FREQUENCY the client waits for the board's next frame (the original
  resends its last one) before it sends anything else. Broadcasts become MEASUREMENT pushes
  numbered by the host from 1 per link (the format has none, so a lost broadcast cannot be
  seen), uptime = time since the link opened.

Not possible: events, configuration, names, clearing latches, and authentication (anyone on
the link can switch; our board's tug front end is read-only unless started with
``--tug-switch``). The ACK carries no command, so ACKs are matched to commands in order. A
board reboot shows only as the link dropping.
"""

from __future__ import annotations

import asyncio
import contextlib
import logging
import socket
from typing import Any

from host.transports.base import PUSH
from host.transports.translate import Handler, TranslatingTransport, WireRefused
from host.transports.url import BoardUrl
from protocol import tug as tw
from protocol.constants import (
    CAP_SUBSCRIBE,
    CAP_VOLTAGE,
    CFG_OK,
    E_BAD_CHANNEL,
    PROTOCOL_VERSION,
    RESET_UNKNOWN,
    ST_OFF,
    ST_ON,
)
from protocol.messages import (
    Ack,
    ChannelStatus,
    GetState,
    Hello,
    Measurement,
    Message,
    Ping,
    Pong,
    PowerCycle,
    State,
    Subscribe,
    Switch,
    Switched,
)

log = logging.getLogger(__name__)

SCHEME = "tug"
SETTLE_S = 1.0  # how long the status may take to follow a CHANNEL command (a busy host)
SPECS_WAIT_S = 1.0  # how long to wait for the SPECIFICATIONS a board sends on connect
AFTER_FREQ_S = 1.5  # longest wait for the board's next frame after SET FREQUENCY

Chans = list[tuple[int, float, float]]


def _on(status: int) -> bool:
    return status == tw.STATUS_ON


class TugTransport(TranslatingTransport):
    SCHEME = SCHEME
    CAPS = frozenset({PUSH})
    MAX_PUSH_HZ = 1.0  # both boards broadcast once a second whatever SET FREQUENCY asked

    def __init__(self, url: BoardUrl, key: bytes | None = None) -> None:
        super().__init__(url, key)
        url.check_params(())
        self.address = url.need_host_port("tug://HOST:PORT")
        self._writer: asyncio.StreamWriter | None = None
        self._lock = asyncio.Lock()
        # waiters: the ACK of the command in flight (and, for REQUEST, the MEASUREMENTS after
        # it), SPECIFICATIONS, MEASUREMENTS, and the next frame of any kind
        self._ack: tuple[asyncio.Future[int], asyncio.Future[bytes] | None] | None = None
        self._waiting: dict[int, list[asyncio.Future[bytes]]] = {
            tw.SPECS: [], tw.MEASUREMENTS: [], -1: []}
        self._freq_sent = False
        self._subscribed = False
        self._seq = 0
        self.n = 0

    async def _open(self) -> Hello:
        reader, self._writer = await asyncio.open_connection(*self.address)
        sock = self._writer.get_extra_info("socket")
        if sock is not None:
            sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
        specs = self._future(tw.SPECS)
        self.spawn(self._read_loop(reader))
        try:
            self.n = (await asyncio.wait_for(specs, SPECS_WAIT_S))[0]
        except TimeoutError:
            self.n = len(await self._measure())
        host, port = self.address
        return Hello(PROTOCOL_VERSION, f"tug@{host}:{port}", "tug", self.n,
                     CAP_SUBSCRIBE | CAP_VOLTAGE, 0, bytes(16), RESET_UNKNOWN, CFG_OK)

    # --- the wire ---------------------------------------------------------------------

    def _future(self, kind: int) -> asyncio.Future[bytes]:
        fut: asyncio.Future[bytes] = asyncio.get_running_loop().create_future()
        self._waiting[kind].append(fut)
        return fut

    async def _read_loop(self, reader: asyncio.StreamReader) -> None:
        decoder = tw.TugDecoder(tw.FROM_BOARD)
        reason = "the board closed the link"
        try:
            while True:
                data = await reader.read(4096)
                if not data:
                    break
                decoder.feed(data)
                for ev in decoder.frames():
                    if isinstance(ev, tw.Bad):
                        log.warning("%s: %s (%d bytes skipped)", self.url.text, ev.reason,
                                    ev.skipped)
                    else:
                        self._dispatch(ev)
        except OSError as exc:
            reason = f"link lost: {exc}"
        self._fail_waiters(reason)
        self.lose(reason)

    def _fail_waiters(self, reason: str) -> None:
        futs: list[asyncio.Future[Any]] = [f for fs in self._waiting.values() for f in fs]
        if self._ack is not None:
            futs.append(self._ack[0])
        for fut in futs:
            if not fut.done():
                fut.set_exception(ConnectionResetError(reason))

    def _wake(self, kind: int, payload: bytes) -> None:
        waiting = self._waiting[kind]
        self._waiting[kind] = []
        for fut in waiting:
            if not fut.done():
                fut.set_result(payload)

    def _dispatch(self, frame: tw.Frame) -> None:
        self._wake(-1, b"")
        if frame.command == tw.ACK:
            pending, self._ack = self._ack, None
            if pending is None or pending[0].done():
                log.debug("%s: an ACK nobody waits for", self.url.text)
                return
            ack, then = pending
            if then is not None:  # a REQUEST: the MEASUREMENTS after this ACK are its answer
                self._waiting[tw.MEASUREMENTS].append(then)
            ack.set_result(frame.payload[0])
            return
        self._wake(frame.command, frame.payload)
        if frame.command == tw.MEASUREMENTS and self._subscribed:
            self._seq += 1
            self.push(self._measurement(tw.parse_measurements(frame.payload)))

    async def _write(self, data: bytes) -> None:
        if self._writer is None:
            raise ConnectionResetError("not connected")
        self._writer.write(data)
        await self._writer.drain()

    async def _command(self, data: bytes, request: bool = False) -> tuple[int, bytes]:
        """Send one command, wait for its ACK (and for a REQUEST the MEASUREMENTS after it):
        ``(ack code, payload)``."""
        loop = asyncio.get_running_loop()
        async with self._lock:
            ack: asyncio.Future[int] = loop.create_future()
            then: asyncio.Future[bytes] | None = loop.create_future() if request else None
            self._ack = (ack, then)
            try:
                await self._write(data)
                code = await ack
                return code, (await then if then is not None else b"")
            finally:
                if self._ack is not None and self._ack[0] is ack:
                    self._ack = None  # given up: a late ACK is dropped, not misassigned
                if then is not None and not then.done():
                    then.cancel()

    async def _measure(self) -> Chans:
        _code, payload = await self._command(tw.request(), request=True)
        chans: Chans = tw.parse_measurements(payload)
        return chans

    async def _switch(self, ch: int, on: bool) -> None:
        if not 0 <= ch <= 0xFF:
            raise WireRefused(E_BAD_CHANNEL, f"no channel {ch}")
        code, _ = await self._command(tw.channel(ch, on))
        if code:
            text = tw.ACK_TEXT.get(code, f"error code {code}")
            raise WireRefused(tw.error_of(code), f"channel {ch}: {text}")

    async def _set_frequency(self, hz: int) -> None:
        async with self._lock:
            nxt = self._future(-1)
            await self._write(tw.set_frequency(max(1, min(hz, 255))))
            with contextlib.suppress(TimeoutError):
                await asyncio.wait_for(nxt, AFTER_FREQ_S)

    def _measurement(self, chans: Chans) -> Measurement:
        on = sum(1 << i for i, c in enumerate(chans) if _on(c[0]))
        mv = round(max((c[2] for c in chans), default=0.0) * 1000)
        return Measurement(self._seq, self.uptime_ms(), max(0, min(mv, 0xFFFF)), on, 0,
                           [round(c[1] * 1000) for c in chans])

    # --- handlers ---------------------------------------------------------------------

    def handlers(self) -> dict[type[Message], Handler]:
        return {GetState: self._get_state, Subscribe: self._subscribe, Switch: self._on_switch,
                PowerCycle: self._on_cycle, Ping: self._ping}

    async def _get_state(self, msg: GetState) -> Message:
        chans = await self._measure()
        out = [ChannelStatus(channel=i, commanded=_on(s), physical=_on(s),
                             state=ST_ON if _on(s) else ST_OFF, current_ma=round(a * 1000),
                             live_faults=0, sticky_faults=0, trips=0, retries=0)
               for i, (s, a, _v) in enumerate(chans)]
        mv = round(max((c[2] for c in chans), default=0.0) * 1000)
        total = sum(c.current_ma for c in out)
        return State(self.uptime_ms(), max(0, min(mv, 0xFFFF)), total, RESET_UNKNOWN, CFG_OK,
                     0, out)

    async def _subscribe(self, msg: Subscribe) -> Message:
        if msg.rate_hz and not self._freq_sent:
            self._freq_sent = True
            await self._set_frequency(msg.rate_hz)
        self._subscribed = msg.rate_hz > 0
        return Ack(Subscribe.TYPE)

    async def _read_back(self, ch: int, want: bool) -> Switched:
        """The channel after a CHANNEL command; our board's status follows the switch at its
        next protection step, so wait up to ``SETTLE_S`` for it to agree."""
        loop = asyncio.get_running_loop()
        end = loop.time() + SETTLE_S
        while True:
            chans = await self._measure()
            if not 0 <= ch < len(chans):
                raise WireRefused(E_BAD_CHANNEL, f"no channel {ch}")
            on = _on(chans[ch][0])
            if on == want or loop.time() >= end:
                return Switched(ch, want, on, ST_ON if on else ST_OFF)
            await asyncio.sleep(0.01)

    async def _ping(self, msg: Ping) -> Message:
        await self._measure()
        return Pong(msg.token, self.uptime_ms())

    async def _disconnect(self) -> None:
        writer, self._writer = self._writer, None
        if writer is not None:
            writer.close()
            with contextlib.suppress(OSError, asyncio.CancelledError):
                await writer.wait_closed()


TRANSPORT = TugTransport
