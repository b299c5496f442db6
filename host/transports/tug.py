"""``tug://HOST:PORT``: the original TEDUSAR power board's format (``tug_codec``) over TCP.

URL grammar: ``tug://HOST:PORT``, no query parameters. For boards already in robots, and for
``dxboard emulate --tug H:P``. The wire knows channels, currents, voltages, on/off and a
broadcast rate, nothing else, so this transport translates (``translate``): on open it asks for
the SPECIFICATIONS (the channel count) and presents a HELLO with board id ``tug@HOST:PORT``,
boot id 0 and no key; GET_STATE asks for MEASUREMENTS; SUBSCRIBE sets the broadcast frequency
and every broadcast becomes a MEASUREMENT numbered by the host from 1 per link (the format
has no sequence numbers, so a lost broadcast cannot be seen), uptime = time since the link
opened; SWITCH sends CHANNEL, waits for the ACK and reads the state back; POWER_CYCLE is off,
wait, on by the host. Not possible: events, configuration, names, clearing latches, and
authentication (anyone on the link can switch). The format has no request ids: replies are
matched to requests by command, first come first served. A board reboot shows only as the
link dropping.
"""

from __future__ import annotations

import asyncio
import collections
import contextlib
import logging

from host.transports import tug_codec as tc
from host.transports.base import PUSH
from host.transports.translate import Handler, Refused, TranslatingTransport
from host.transports.url import BoardUrl
from protocol.constants import (
    CAP_SUBSCRIBE,
    CAP_VOLTAGE,
    CFG_OK,
    E_INTERNAL,
    E_SWITCH_FAULT,
    F_SHORT,
    PROTOCOL_VERSION,
    RESET_UNKNOWN,
    ST_OFF,
    ST_ON,
    ST_TRIPPED,
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
SETTLE_S = 0.3  # how long the status may take to follow a CHANNEL command


def _state(status: int) -> int:
    if status & tc.STATUS_FAULT:
        return ST_TRIPPED
    return ST_ON if status & tc.STATUS_ON else ST_OFF


class TugTransport(TranslatingTransport):
    SCHEME = SCHEME
    CAPS = frozenset({PUSH})

    def __init__(self, url: BoardUrl, key: bytes | None = None) -> None:
        super().__init__(url, key)
        url.check_params(())
        self.address = url.need_host_port("tug://HOST:PORT")
        self._reader: asyncio.StreamReader | None = None
        self._writer: asyncio.StreamWriter | None = None
        self._waiters: dict[int, collections.deque[asyncio.Future[bytes]]] = \
            collections.defaultdict(collections.deque)
        self._subscribed = False
        self._seq = 0
        self.n = 0

    async def _open(self) -> Hello:
        self._reader, self._writer = await asyncio.open_connection(*self.address)
        self.spawn(self._read_loop())
        specs = tc.parse_specs(await self._ask(tc.request(tc.SPECS), tc.SPECS))
        self.n = len(specs)
        host, port = self.address
        return Hello(PROTOCOL_VERSION, f"tug@{host}:{port}", "tug", self.n,
                     CAP_SUBSCRIBE | CAP_VOLTAGE, 0, bytes(16), RESET_UNKNOWN, CFG_OK)

    async def _read_loop(self) -> None:
        decoder = tc.Decoder()
        reader = self._reader
        if reader is None:
            return
        while True:
            try:
                data = await reader.read(4096)
            except OSError as exc:
                self.lose(f"link lost: {exc}")
                return
            if not data:
                self.lose("the board closed the link")
                return
            decoder.feed(data)
            for frame in decoder.frames():
                if isinstance(frame, tc.TugBad):
                    log.warning("%s: %s (%d bytes skipped)", self.url.text, frame.reason,
                                frame.skipped)
                    continue
                self._dispatch(frame)

    def _dispatch(self, frame: tc.TugFrame) -> None:
        key = frame.command
        if key == tc.ACK:
            key = 0x100 | frame.payload[0]
        waiters = self._waiters[key]
        while waiters:
            fut = waiters.popleft()
            if not fut.done():
                fut.set_result(frame.payload)
                if key != tc.MEASUREMENTS:
                    break
        if frame.command == tc.MEASUREMENTS and self._subscribed:
            self._seq += 1
            self.push(self._measurement(tc.parse_measurements(frame.payload)))

    def _measurement(self, chans: list[tuple[int, float, float]]) -> Measurement:
        on = sum(1 << i for i, c in enumerate(chans) if c[0] & tc.STATUS_ON)
        fault = sum(1 << i for i, c in enumerate(chans) if c[0] & tc.STATUS_FAULT)
        mv = round(max((c[2] for c in chans), default=0.0) * 1000)
        return Measurement(self._seq, self.uptime_ms(), min(mv, 0xFFFF), on, fault,
                           [round(c[1] * 1000) for c in chans])

    async def _ask(self, data: bytes, answer: int) -> bytes:
        fut: asyncio.Future[bytes] = asyncio.get_running_loop().create_future()
        self._waiters[answer].append(fut)
        await self._write(data)
        return await fut

    async def _write(self, data: bytes) -> None:
        if self._writer is None:
            raise ConnectionResetError("not connected")
        self._writer.write(data)
        await self._writer.drain()

    async def _measure(self) -> list[tuple[int, float, float]]:
        return tc.parse_measurements(await self._ask(tc.request(tc.MEASUREMENTS),
                                                     tc.MEASUREMENTS))

    async def _switch(self, ch: int, on: bool) -> None:
        payload = await self._ask(tc.channel(ch, on), 0x100 | tc.CHANNEL)
        if payload[1]:
            raise Refused(E_SWITCH_FAULT, f"the tug board refused to switch channel {ch}")

    # --- handlers ---------------------------------------------------------------------

    def handlers(self) -> dict[type[Message], Handler]:
        return {GetState: self._get_state, Subscribe: self._subscribe, Switch: self._on_switch,
                PowerCycle: self._on_cycle, Ping: self._ping}

    async def _get_state(self, msg: GetState) -> Message:
        chans = await self._measure()
        out = [ChannelStatus(channel=i, commanded=bool(s & tc.STATUS_ON),
                             physical=bool(s & tc.STATUS_ON), state=_state(s),
                             current_ma=round(a * 1000),
                             live_faults=F_SHORT if s & tc.STATUS_FAULT else 0,
                             sticky_faults=0, trips=0, retries=0)
               for i, (s, a, _v) in enumerate(chans)]
        mv = round(max((c[2] for c in chans), default=0.0) * 1000)
        total = sum(c.current_ma for c in out)
        return State(self.uptime_ms(), min(mv, 0xFFFF), total, RESET_UNKNOWN, CFG_OK, 0, out)

    async def _subscribe(self, msg: Subscribe) -> Message:
        payload = await self._ask(tc.set_frequency(msg.rate_hz), 0x100 | tc.SET_FREQ)
        if payload[1]:
            raise Refused(E_INTERNAL, "the tug board refused the broadcast frequency")
        self._subscribed = msg.rate_hz > 0
        return Ack(Subscribe.TYPE)

    async def _read_back(self, ch: int, want: bool) -> Switched:
        """The channel after a CHANNEL command; the board's status follows the switch at its
        next measurement, so wait up to ``SETTLE_S`` for it to agree."""
        loop = asyncio.get_running_loop()
        end = loop.time() + SETTLE_S
        while True:
            chans = await self._measure()
            if not 0 <= ch < len(chans):
                raise Refused(E_SWITCH_FAULT, f"no channel {ch}")
            status = chans[ch][0]
            on = bool(status & tc.STATUS_ON)
            if on == want or loop.time() >= end:
                return Switched(ch, want, on, _state(status))
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
