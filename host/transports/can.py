"""``can://INTERFACE/CHANNEL``: the board's CAN node (``protocol/dxboard.dbc``) with python-can.

URL grammar: ``can://INTERFACE/CHANNEL[?node=N&bitrate=B&channels=C]``: INTERFACE a python-can
interface (``socketcan``, ``virtual``, ``udp_multicast``, ...), CHANNEL its channel (``can0``,
``vcan0``, a multicast group such as ``239.74.163.2``); node = the board's node id N (0-15,
default 0); bitrate for interfaces that set it; channels = the channel count (default: learnt
from the DXB_Channel broadcasts). Frames are Intel byte order as the DBC says.

CAN has no request/reply: the board broadcasts DXB_Status, DXB_Nonce and DXB_Channel_k every
second and DXB_Currents_g at its CAN rate. So this transport translates: opening waits (up to
about a second) for the nonce, the status and one round of channel frames and presents a HELLO
with board id ``can@INTERFACE/CHANNEL/N`` and boot id = the first 4 bytes of the boot's nonce
(a new nonce is a reboot: a fresh HELLO is pushed); GET_STATE answers from the latest
broadcasts (at most a second old; uptime in whole seconds); SUBSCRIBE delivers a MEASUREMENT
for each complete set of DXB_Currents frames, numbered by the host (the board's CAN rate
applies, whatever rate is asked; currents in 10 mA steps); SWITCH, POWER_CYCLE (off time in
100 ms steps) and CLEAR are DXB_Cmd + DXB_CmdTagA/B authenticated with the key (HMAC over the
nonce and the command, ``protocol.auth``) answered by DXB_CmdResult. The command counter must
rise across host restarts too, so it is ``max(last + 1, tenths of a second since 2024)``. Not
possible over CAN: events, configuration, names, saving.
"""

from __future__ import annotations

import asyncio
import collections
import contextlib
import logging
import struct
import time
from typing import Any

import can as pycan

from host.transports.base import AUTH, BOOT_ID, CYCLE, PUSH
from host.transports.translate import Handler, RangeEvents, TranslatingTransport, WireRefused
from host.transports.url import BoardUrl
from protocol import can as layout
from protocol.can import (
    ID_CMD,
    ID_NONCE,
    ID_RESULT,
    ID_STATUS,
    ID_TAG_A,
    ID_TAG_B,
    OP_CLEAR,
    OP_CYCLE,
    OP_OFF,
    OP_ON,
    channel_id,
    currents_id,
)
from protocol.constants import (
    CAP_AUTH,
    CAP_CAN,
    CAP_SUBSCRIBE,
    E_AUTH_REQUIRED,
    NOT_FAULTS,
    PROTOCOL_VERSION,
    ST_OFF,
)
from protocol.messages import (
    Ack,
    ChannelStatus,
    Clear,
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

SCHEME = "can"
EPOCH_2024 = 1704067200.0
SETTLE_S = 0.15  # after the first broadcasts, how long to collect a round of channel frames


class CanTransport(TranslatingTransport):
    SCHEME = SCHEME
    CAPS = frozenset({PUSH, AUTH, CYCLE, BOOT_ID})

    def __init__(self, url: BoardUrl, key: bytes | None = None) -> None:
        super().__init__(url, key)
        url.check_params(("node", "bitrate", "channels"))
        self.interface = url.host
        self.channel = url.path.strip("/")
        if not self.interface or not self.channel:
            url.need_path("CAN channel", "can://socketcan/can0 or can://virtual/ch0")
        self.node = url.int_param("node", 0, 0, 15)
        self.bitrate = url.int_param("bitrate", 0, 0, 8_000_000)
        self.fixed_n = url.int_param("channels", 0, 0, 16)
        self.bus: Any = None
        self.notifier: Any = None
        self.nonce = b""
        self.status: tuple[int, int, int, int, int] | None = None  # uptime s, mV, flags, rc, cs
        self.status_at = 0.0
        self.chan: dict[int, tuple[int, bool, bool, int, int, int, int]] = {}
        self.currents: dict[int, list[int]] = {}
        self.n = 0
        self.counter = 0
        self._seq = 0
        self._ranges = RangeEvents()  # the low flag's range EVENTs (no events on CAN)
        self._subscribed = False
        self._results: dict[tuple[int, int], collections.deque[asyncio.Future[bytes]]] = \
            collections.defaultdict(collections.deque)
        self._seen = asyncio.Event()

    # --- bus --------------------------------------------------------------------------

    async def _open(self) -> Hello:
        kw: dict[str, Any] = {"interface": self.interface, "channel": self.channel}
        if self.bitrate:
            kw["bitrate"] = self.bitrate
        try:
            self.bus = pycan.Bus(**kw)
        except (pycan.CanError, ImportError, ValueError) as exc:
            raise OSError(f"cannot open CAN {self.interface}/{self.channel}: {exc}") from exc
        reader = pycan.AsyncBufferedReader()
        self.notifier = pycan.Notifier(self.bus, [reader], loop=asyncio.get_running_loop())
        self.spawn(self._read_loop(reader))
        while not (self.nonce and self.status and self.chan):
            self._seen.clear()
            await self._seen.wait()
        await asyncio.sleep(SETTLE_S)
        self.n = self.fixed_n or max(self.chan) + 1
        return self._hello()

    def _hello(self) -> Hello:
        rc, cs = (self.status[3], self.status[4]) if self.status else (0, 0)
        return Hello(PROTOCOL_VERSION, f"can@{self.interface}/{self.channel}/{self.node}",
                     "can", self.n, CAP_AUTH | CAP_SUBSCRIBE | CAP_CAN,
                     int.from_bytes(self.nonce[:4], "little"), bytes(16), rc, cs)

    async def _read_loop(self, reader: Any) -> None:
        async for msg in reader:
            if msg.is_error_frame or msg.is_remote_frame:
                continue
            try:
                self._frame(msg.arbitration_id, bytes(msg.data))
            except (ValueError, struct.error, IndexError) as exc:
                log.warning("%s: bad frame 0x%03x: %s", self.url.text, msg.arbitration_id, exc)

    def _frame(self, can_id: int, data: bytes) -> None:
        n = self.node
        if can_id == ID_NONCE + n:
            if self.nonce and data != self.nonce and self.n:
                self.nonce = data
                self.push(self._hello())  # a new nonce: the board rebooted
            self.nonce = data
        elif can_id == ID_STATUS + n:
            self.status = layout.parse_status(data)
            self.status_at = time.monotonic()
        elif channel_id(n, 0) <= can_id < channel_id(n, 16):
            self.chan[can_id - channel_id(n, 0)] = layout.parse_channel(data)
        elif currents_id(n, 0) <= can_id < currents_id(n, layout.CURRENT_GROUPS):
            g = can_id - currents_id(n, 0)
            self.currents[g] = layout.parse_currents(data)
            if self._subscribed and self.n and g == (self.n - 1) // 4:
                self._seq += 1
                reading = self._measurement()
                chans = [self.chan.get(k, (ST_OFF, False, False, 0, 0, 0, 0))
                         for k in range(self.n)]
                for ev in self._ranges.changes(reading.uptime_ms, [c[4] for c in chans],
                                               [c[0] for c in chans], reading.currents_ma):
                    self.push(ev)
                self.push(reading)
        elif can_id == ID_RESULT + n:
            op, ch = layout.parse_result(data)[:2]
            waiters = self._results[(op, ch)]
            while waiters:
                fut = waiters.popleft()
                if not fut.done():
                    fut.set_result(data)
                    break
        self._seen.set()

    def _uptime(self) -> int:
        if self.status is None:
            return 0
        return (self.status[0] * 1000 + int((time.monotonic() - self.status_at) * 1000)) \
            & 0xFFFFFFFF

    def _measurement(self) -> Measurement:
        currents = [self.currents.get(k // 4, [0] * 4)[k % 4] for k in range(self.n)]
        on = sum(1 << k for k, c in self.chan.items() if c[2] and k < self.n)
        bad = sum(1 << k for k, c in self.chan.items() if c[4] & ~NOT_FAULTS and k < self.n)
        mv = self.status[1] if self.status else 0
        return Measurement(self._seq, self._uptime(), mv, on, bad, currents)

    async def _command(self, op: int, ch: int, force: bool = False, off_100ms: int = 0) -> bytes:
        if self.key is None:
            raise WireRefused(E_AUTH_REQUIRED, "no key: set DXBOARD_KEY or --key-file")
        self.counter = max(self.counter + 1, int((time.time() - EPOCH_2024) * 10))
        cmd = layout.command_frame(op, ch, force, off_100ms, self.counter & 0xFFFFFFFF)
        tag = layout.command_tag(self.key, self.nonce, cmd)
        fut: asyncio.Future[bytes] = asyncio.get_running_loop().create_future()
        self._results[(op, ch)].append(fut)
        n = self.node
        for can_id, data in ((ID_CMD + n, cmd), (ID_TAG_A + n, tag[:8]), (ID_TAG_B + n, tag[8:])):
            try:
                self.bus.send(pycan.Message(arbitration_id=can_id, data=data,
                                            is_extended_id=False))
            except pycan.CanError as exc:
                raise OSError(f"CAN send failed: {exc}") from exc
        result = await fut
        err = layout.parse_result(result)[2]
        if err:
            raise WireRefused(err)
        return result

    @staticmethod
    def _switched(result: bytes, commanded: bool) -> Switched:
        _op, ch, _err, state, physical = layout.parse_result(result)
        return Switched(ch, commanded, physical, state)

    # --- handlers ---------------------------------------------------------------------

    def handlers(self) -> dict[type[Message], Handler]:
        return {GetState: self._get_state, Subscribe: self._subscribe, Switch: self._on_switch,
                PowerCycle: self._on_cycle, Clear: self._on_clear, Ping: self._ping}

    def supports(self, msg: Message) -> bool:
        return not isinstance(msg, Clear) or msg.channel < 16

    async def _get_state(self, msg: GetState) -> Message:
        chans = []
        for k in range(self.n):
            st, cmd, phys, ma, live, trips, retries = self.chan.get(
                k, (ST_OFF, False, False, 0, 0, 0, 0))
            chans.append(ChannelStatus(channel=k, commanded=cmd, physical=phys, state=st,
                                       current_ma=ma, live_faults=live, sticky_faults=0,
                                       trips=trips, retries=retries))
        _up, mv, flags, rc, cs = self.status or (0, 0, 0, 0, 0)
        total = sum(c.current_ma for c in chans)
        return State(self._uptime(), mv, total, rc, cs, flags, chans)

    async def _subscribe(self, msg: Subscribe) -> Message:
        self._subscribed = msg.rate_hz > 0
        return Ack(Subscribe.TYPE)

    async def _on_switch(self, msg: Switch) -> Message:
        result = await self._command(OP_ON if msg.on else OP_OFF, msg.channel, msg.force)
        return self._switched(result, msg.on)

    async def _on_cycle(self, msg: PowerCycle) -> Message:
        off = min(255, round(msg.off_ms / 100))
        return self._switched(await self._command(OP_CYCLE, msg.channel, msg.force, off), True)

    async def _on_clear(self, msg: Clear) -> Message:
        result = await self._command(OP_CLEAR, msg.channel)
        return self._switched(result, False)

    async def _ping(self, msg: Ping) -> Message:
        return Pong(msg.token, self._uptime())

    async def _disconnect(self) -> None:
        if self.notifier is not None:
            self.notifier.stop()
        if self.bus is not None:
            with contextlib.suppress(pycan.CanError):
                self.bus.shutdown()
        self.bus = self.notifier = None


TRANSPORT = CanTransport
