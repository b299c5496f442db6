"""``modbus+tcp://HOST:PORT`` and ``modbus+rtu:///dev/ttyUSB0``: a board (or a third-party relay
or power board) read and switched over Modbus with pymodbus.

URL grammar: ``modbus+tcp://HOST:PORT[?unit=N&map=FILE]`` and
``modbus+rtu://DEVICE[?baud=N&unit=N&map=FILE]`` (DEVICE an absolute path; baud default 19200,
8N1; unit default 1; the dxboard board answers any unit). ``map`` names a JSON register map; the
default is the board's own map (PROTOCOL.md, ``BOARD_MAP`` below). A map file replaces it
entirely: every key is optional and a missing one means "this device does not have it" (no
currents: 0; no read-back inputs: the coils are read back; no channel count register:
``channels``). Keys: ``channels`` or ``channel_count`` (input register), ``version`` (input
register; absent = assumed compatible), ``switch_coils`` (coil of channel 0), ``readback_inputs``
and ``fault_inputs`` (discrete input of channel 0), ``current_registers`` (input register of
channel 0, with ``current_scale`` mA per count), ``state_registers``, ``live_fault_registers``,
``sticky_fault_registers``, ``trip_registers`` (input registers of channel 0), ``input_mv``,
``board_flags``, ``reset_cause``, ``config_status`` (input registers), ``total_ma``,
``uptime_ms`` and ``boot_id`` (two input registers, high word first), ``save_register``/
``save_value`` (holding register written to persist the configuration).

What Modbus cannot do, and what this transport does instead: no push, so SUBSCRIBE starts a
poll at that rate and each poll becomes a MEASUREMENT numbered by the host (a poll that fails
is a gap in that numbering); no authentication, so no key is sent and the board accepts writes
only from the client addresses its config allows (exception 01 otherwise, reported as such);
no power cycle, so it is off, wait, on timed by the host; no events, no clearing, no channel
names, no configuration through the client (``save`` only). The HELLO is made up from the
registers: board id ``modbus@HOST:PORT/N``, the protocol version register, and the boot id
registers (110-111), random at every boot, so a new one is a reboot (capability ``boot_id``).
A device without them (a map that has none, or a board whose firmware predates them: exception
02 for 110 with the default map) gets boot id 0 and one more each time the uptime register goes
backwards (a reboot seen between two polls), and the link tells a reboot by an uptime that fell
behind the time it was away. A device
that does not answer as its map says (a channel count of 0 or too many, a register it does
not have, exception 04 for a unit id it does not serve) is ``UnexpectedDevice`` on opening:
one line naming the register or the unit and how to describe the device instead.
"""

from __future__ import annotations

import asyncio
import json
import logging
from dataclasses import dataclass
from typing import Any

from pymodbus.client import AsyncModbusSerialClient, AsyncModbusTcpClient
from pymodbus.exceptions import ModbusException

from host.transports.base import BOOT_ID, PUSH, SAVE
from host.transports.errors import BadUrl, UnexpectedDevice
from host.transports.translate import Handler, RangeEvents, TranslatingTransport, WireRefused
from host.transports.url import BoardUrl
from protocol import modbus_map as M
from protocol.constants import (
    CAP_SUBSCRIBE,
    CFG_OK,
    E_BAD_CHANNEL,
    E_BAD_VALUE,
    E_INHIBITED,
    E_INTERNAL,
    NOT_FAULTS,
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
    SaveConfig,
    State,
    Subscribe,
    Switch,
    Switched,
)

log = logging.getLogger(__name__)

BOARD_MAP: dict[str, Any] = {  # the board's own map (protocol/modbus_map.py)
    "channel_count": M.CHANNEL_COUNT, "version": M.VERSION, "switch_coils": 0,
    "readback_inputs": 0, "fault_inputs": M.FAULT_INPUTS, "current_registers": M.CURRENT,
    "current_scale": 1.0, "state_registers": M.STATE, "live_fault_registers": M.LIVE_FAULTS,
    "sticky_fault_registers": M.STICKY_FAULTS, "trip_registers": M.TRIPS,
    "input_mv": M.INPUT_MV, "total_ma": M.TOTAL_MA, "uptime_ms": M.UPTIME_MS,
    "boot_id": M.BOOT_ID, "board_flags": M.BOARD_FLAGS, "reset_cause": M.RESET_CAUSE,
    "config_status": M.CONFIG_STATUS, "save_register": M.CMD_REG, "save_value": M.CMD_SAVE,
}
_KEYS = set(BOARD_MAP) | {"channels"}
_EXCEPTIONS = {
    M.X_FUNCTION: (E_INHIBITED, "Modbus writes are not enabled for this client (exception 01): "
                     "set modbus_write and modbus_allow in the board config"),
    M.X_ADDRESS: (E_BAD_CHANNEL, "no such register (exception 02)"),
    M.X_VALUE: (E_BAD_VALUE, "value refused (exception 03)"),
    M.X_DEVICE: (E_INTERNAL, "refused by the board (exception 04)"),
}
SPAN = 120  # registers per read request (Modbus allows 125)
SETTLE_S = 0.3  # how long a switch's read-back may take to follow a write


def load_map(path: str) -> dict[str, Any]:
    try:
        with open(path) as f:
            data = json.load(f)
    except OSError as exc:
        raise BadUrl(f"cannot read the register map {path}: {exc.strerror}",
                     "give an existing JSON file with map=FILE") from None
    except ValueError as exc:
        raise BadUrl(f"register map {path} is not JSON: {exc}", "fix the file") from None
    if not isinstance(data, dict) or set(data) - _KEYS:
        bad = sorted(set(data) - _KEYS) if isinstance(data, dict) else ["?"]
        raise BadUrl(f"register map {path}: unknown key(s) {', '.join(bad)}",
                     "keys: " + ", ".join(sorted(_KEYS)))
    if "channels" not in data and "channel_count" not in data:
        raise BadUrl(f"register map {path} says neither channels nor channel_count",
                     'add e.g. "channels": 4')
    return data


@dataclass
class Snapshot:
    commanded: list[bool]
    physical: list[bool]
    faulty: list[bool]
    current_ma: list[int]
    state: list[int]
    live: list[int]
    sticky: list[int]
    trips: list[int]
    input_mv: int
    total_ma: int
    uptime_ms: int | None
    flags: int
    reset_cause: int
    config_status: int
    boot_id: int | None = None


class ModbusTransport(TranslatingTransport):
    CAPS = frozenset({PUSH, SAVE})

    def __init__(self, url: BoardUrl, key: bytes | None = None) -> None:
        super().__init__(url, None)  # Modbus has no authentication: the key is never sent
        self.unit = url.int_param("unit", 1, 0, 247)
        self.map = load_map(url.query["map"]) if "map" in url.query else dict(BOARD_MAP)
        self.custom_map = "map" in url.query
        self._reading = ""
        if url.scheme == "modbus+tcp":
            url.check_params(("unit", "map"))
            host, port = url.need_host_port("modbus+tcp://HOST:PORT")
            self.where = f"{host}:{port}"
            self._make: Any = lambda: AsyncModbusTcpClient(host, port=port, timeout=2,
                                                           retries=0, reconnect_delay=0)
        else:
            url.check_params(("unit", "map", "baud"))
            device = url.need_path("device", "modbus+rtu:///dev/ttyUSB0?baud=19200&unit=1")
            baud = url.int_param("baud", 19200, 300, 4_000_000)
            self.where = device
            self._make = lambda: AsyncModbusSerialClient(device, baudrate=baud, timeout=2,
                                                         retries=0, reconnect_delay=0)
        self.client: Any = None  # made in _open: pymodbus needs the running loop
        self.n = 0
        self.boot = 0
        self._last_uptime = -1
        self._seq = 0
        self._ranges = RangeEvents()  # the low flag's range EVENTs (no events on Modbus)
        self._poller: asyncio.Task[None] | None = None
        self._lock = asyncio.Lock()

    @property
    def caps(self) -> frozenset[str]:
        """``CAPS``, and ``boot_id`` when the device has the boot id registers."""
        return self.CAPS | {BOOT_ID} if self.map.get("boot_id") is not None else self.CAPS

    # --- wire -------------------------------------------------------------------------

    async def _call(self, name: str, *args: Any, **kw: Any) -> Any:
        async with self._lock:  # one transaction at a time (RTU is half duplex anyway)
            try:
                reply = await getattr(self.client, name)(*args, device_id=self.unit, **kw)
            except ModbusException as exc:
                raise ConnectionResetError(f"Modbus: {exc}") from exc
        if reply.isError():
            code, text = _EXCEPTIONS.get(reply.exception_code, (E_INTERNAL, "Modbus exception"))
            raise WireRefused(code, text, reply.exception_code)
        return reply

    async def _bits(self, fn: str, base: int, n: int) -> list[bool]:
        reply = await self._call(fn, base, count=n)
        return [bool(b) for b in reply.bits[:n]]

    async def _registers(self, addresses: list[int]) -> dict[int, int]:
        out: dict[int, int] = {}
        todo = sorted(set(addresses))
        while todo:
            start = todo[0]
            chunk = [a for a in todo if a < start + SPAN]
            reply = await self._call("read_input_registers", start, count=chunk[-1] - start + 1)
            for a in chunk:
                out[a] = reply.registers[a - start]
            todo = todo[len(chunk):]
        return out

    async def snapshot(self) -> Snapshot:
        m, n = self.map, self.n
        addrs: list[int] = []
        per_channel = ("current_registers", "state_registers", "live_fault_registers",
                       "sticky_fault_registers", "trip_registers")
        for key in per_channel:
            if m.get(key) is not None:
                addrs += [m[key] + k for k in range(n)]
        for key in ("input_mv", "board_flags", "reset_cause", "config_status"):
            if m.get(key) is not None:
                addrs.append(m[key])
        for key in ("total_ma", "uptime_ms", "boot_id"):
            if m.get(key) is not None:
                addrs += [m[key], m[key] + 1]
        regs = await self._registers(addrs) if addrs else {}

        def chan(key: str, scale: float = 1.0) -> list[int]:
            base = m.get(key)
            return [round(regs[base + k] * scale) if base is not None else 0 for k in range(n)]

        def one(key: str, default: int = 0) -> int:
            return regs[m[key]] if m.get(key) is not None else default

        def u32(key: str) -> int | None:
            a = m.get(key)
            return (regs[a] << 16 | regs[a + 1]) if a is not None else None

        commanded = await self._bits("read_coils", m["switch_coils"], n)
        physical = (await self._bits("read_discrete_inputs", m["readback_inputs"], n)
                    if m.get("readback_inputs") is not None else list(commanded))
        faulty = (await self._bits("read_discrete_inputs", m["fault_inputs"], n)
                  if m.get("fault_inputs") is not None else [False] * n)
        states = chan("state_registers") if m.get("state_registers") is not None else \
            [ST_ON if p else ST_OFF for p in physical]
        currents = chan("current_registers", float(m.get("current_scale", 1.0)))
        total = u32("total_ma")
        return Snapshot(commanded, physical, faulty, currents, states,
                        chan("live_fault_registers"), chan("sticky_fault_registers"),
                        chan("trip_registers"), one("input_mv"),
                        sum(currents) if total is None else total, u32("uptime_ms"),
                        one("board_flags"), one("reset_cause", RESET_UNKNOWN),
                        one("config_status", CFG_OK), u32("boot_id"))

    def _uptime(self, snap: Snapshot) -> int:
        if snap.boot_id is not None:  # the board's own: a new one is a reboot
            if snap.boot_id != self.boot:
                self.boot = snap.boot_id
                self.push(self._hello(snap))
        elif snap.uptime_ms is not None and 0 <= snap.uptime_ms < self._last_uptime:
            self.boot += 1  # went backwards: the board rebooted
            self.push(self._hello(snap))
        if snap.uptime_ms is None:
            return self.uptime_ms()
        self._last_uptime = snap.uptime_ms
        return snap.uptime_ms

    def _hello(self, snap: Snapshot) -> Hello:
        return Hello(self._version, f"modbus@{self.where}/{self.unit}", "modbus", self.n,
                     CAP_SUBSCRIBE, self.boot, bytes(16), snap.reset_cause, snap.config_status)

    # --- open, poll, close ------------------------------------------------------------

    async def _open(self) -> Hello:
        self.client = self._make()
        if not await self.client.connect():
            raise ConnectionRefusedError(f"no Modbus server at {self.where}")
        try:
            return await self._learn(self.map)
        except WireRefused as exc:
            raise self._unexpected(exc) from None

    async def _learn(self, m: dict[str, Any]) -> Hello:
        """Channel count, version and a first snapshot, read from the device."""
        fixed = m.get("channels")
        head = [a for a in (m.get("channel_count"), m.get("version")) if a is not None]
        self._reading = " and ".join(
            f"the {what} (input register {m[key]})" for key, what in
            (("channel_count", "channel count"), ("version", "version")) if m.get(key) is not None)
        regs = await self._registers(head) if head else {}
        n = int(fixed) if fixed is not None else regs[m["channel_count"]]
        limit = 255 if self.custom_map else M.MAX_CHANNELS
        if not 1 <= n <= limit:
            where = ("the map's \"channels\"" if fixed is not None else
                     f"input register {m['channel_count']}")
            raise UnexpectedDevice(f"{self.url.text}: the device reports {n} channels "
                                   f"({where}); expected 1..{limit}",
                                   "is it a dxboard board? describe another device with "
                                   '?map=FILE ("channels": N, ...)')
        self.n = n
        self._version = regs[m["version"]] if m.get("version") is not None else PROTOCOL_VERSION
        if not self.custom_map and m.get("boot_id") is not None:
            try:
                await self._registers([m["boot_id"], m["boot_id"] + 1])
            except WireRefused as exc:
                if exc.modbus != M.X_ADDRESS:
                    raise
                log.info("%s: no boot id registers (firmware before them): a reboot is told "
                         "by the uptime", self.url.text)
                del m["boot_id"]
        self._reading = "the registers of the map"
        snap = await self.snapshot()
        self._last_uptime = snap.uptime_ms if snap.uptime_ms is not None else -1
        if snap.boot_id is not None:
            self.boot = snap.boot_id
        return self._hello(snap)

    def _unexpected(self, exc: WireRefused) -> UnexpectedDevice:
        if exc.modbus == M.X_DEVICE:
            return UnexpectedDevice(
                f"{self.url.text}: the device answered exception 04 (device failure) for "
                f"unit {self.unit} while reading {self._reading}",
                "is that its unit id? give the right one with ?unit=N")
        return UnexpectedDevice(
            f"{self.url.text}: unit {self.unit} refused reading {self._reading}: {exc.text}",
            "is it a dxboard board? describe another device with ?map=FILE")

    async def _poll(self, rate_hz: int) -> None:
        period = 1 / rate_hz
        loop = asyncio.get_running_loop()
        due = loop.time()
        while True:
            self._seq += 1
            try:
                snap = await self.snapshot()
            except WireRefused as exc:
                log.warning("%s: poll refused: %s", self.url.text, exc)
            except OSError as exc:
                self.lose(f"link lost while polling: {exc}")
                return
            else:
                up = self._uptime(snap)
                on = sum(1 << k for k, p in enumerate(snap.physical) if p)
                bad = sum(1 << k for k in range(self.n)
                          if snap.faulty[k] or snap.live[k] & ~NOT_FAULTS)
                for ev in self._ranges.changes(up, snap.live, snap.state, snap.current_ma):
                    self.push(ev)
                self.push(Measurement(self._seq, up, min(snap.input_mv, 0xFFFF), on, bad,
                                      snap.current_ma))
            due = max(due + period, loop.time())
            await asyncio.sleep(due - loop.time())

    async def _disconnect(self) -> None:
        if self._poller is not None:
            self._poller.cancel()
        if self.client is not None:
            self.client.close()

    # --- handlers ---------------------------------------------------------------------

    def handlers(self) -> dict[type[Message], Handler]:
        return {GetState: self._get_state, Subscribe: self._subscribe, Switch: self._on_switch,
                PowerCycle: self._on_cycle, Ping: self._ping, SaveConfig: self._save}

    def supports(self, msg: Message) -> bool:
        return not isinstance(msg, SaveConfig) or self.map.get("save_register") is not None

    async def _get_state(self, msg: GetState) -> Message:
        s = await self.snapshot()
        chans = [ChannelStatus(channel=k, commanded=s.commanded[k], physical=s.physical[k],
                               state=s.state[k], current_ma=s.current_ma[k],
                               live_faults=s.live[k], sticky_faults=s.sticky[k],
                               trips=s.trips[k], retries=0) for k in range(self.n)]
        return State(self._uptime(s), min(s.input_mv, 0xFFFF), s.total_ma, s.reset_cause,
                     s.config_status, s.flags, chans)

    async def _subscribe(self, msg: Subscribe) -> Message:
        if self._poller is not None:
            self._poller.cancel()
            self._poller = None
        if msg.rate_hz:
            self._poller = self.spawn(self._poll(msg.rate_hz))
        return Ack(Subscribe.TYPE)

    async def _switch(self, ch: int, on: bool) -> None:
        if not 0 <= ch < self.n:
            raise WireRefused(E_BAD_CHANNEL)
        await self._call("write_coil", self.map["switch_coils"] + ch, on)

    async def _read_back(self, ch: int, want: bool) -> Switched:
        """The channel after a write; the registers follow the switch at the board's next
        protection step, so wait up to ``SETTLE_S`` for the read-back to agree."""
        loop = asyncio.get_running_loop()
        end = loop.time() + SETTLE_S
        while True:
            s = await self.snapshot()
            if s.physical[ch] == want or loop.time() >= end:
                return Switched(ch, s.commanded[ch], s.physical[ch], s.state[ch])
            await asyncio.sleep(0.01)

    async def _ping(self, msg: Ping) -> Message:
        s = await self.snapshot()
        return Pong(msg.token, self._uptime(s))

    async def _save(self, msg: SaveConfig) -> Message:
        await self._call("write_register", self.map["save_register"],
                         int(self.map.get("save_value", 1)))
        return Ack(SaveConfig.TYPE)


class ModbusTcpTransport(ModbusTransport):
    SCHEME = "modbus+tcp"


class ModbusRtuTransport(ModbusTransport):
    SCHEME = "modbus+rtu"


TRANSPORT = ModbusTcpTransport
TRANSPORTS = {"modbus+tcp": ModbusTcpTransport, "modbus+rtu": ModbusRtuTransport}
