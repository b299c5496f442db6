"""Modbus TCP server of the board (PROTOCOL.md §8): MBAP framing, the register map, asyncio.

Sans I/O first: ``Framer`` splits a byte stream into MBAP requests; ``handle(board, request,
client_ip) -> bytes`` answers one whole ADU; ``serve(net, host, port)`` is the asyncio wrapper
(the board comes from ``net.app``, so it follows reboots). Frames::

    +--------+--------+--------+------+------+----------+
    | trans  | proto  | length | unit |  fc  |   data   |     (big-endian u16s)
    +--------+--------+--------+------+------+----------+
        2        2        2       1      1     length-2

Any unit id is answered. A protocol id other than 0 or a length above 254 (or below 2)
closes the connection. The register map is ``protocol/modbus_map.py`` (PROTOCOL.md §8), the
configuration fields ``protocol/settings.py``; ``protected`` is never writable here: writing
a value other than the current one is exception 02.

Requests reaching outside a table's span get exception 02; unassigned addresses inside it read
0 and are not writable (02). Counts out of range or bad values: 03. Writes need
``modbus_write`` and the client's IPv4 address in ``modbus_allow``, else 01; an unknown
function is 01; the board refusing (latched, protected, switch fault, inhibited, storage) is
04. A write is checked completely before anything changes: FC15 checks every coil with
``Board.check_switch`` before it switches any. The client's address is the socket's peer
(``peer_ip`` reads CPython's tuple and MicroPython's raw sockaddr alike), or with
``proxied`` the one named by the PROXY line the emulator's link proxy sends first.
"""

import asyncio
import struct

from protocol import settings
from protocol.constants import E_BAD_CHANNEL, NOT_FAULTS, PROTOCOL_VERSION
from protocol.modbus_map import (
    BOARD_FLAGS,
    BOARD_REGS,
    BOARD_REGS_END,
    BOOT_ID,
    CH_BASE,
    CH_REGS,
    CH_STRIDE,
    CHANNEL_COUNT,
    CMD_REG,
    CMD_SAVE,
    COIL_SPAN,
    CONFIG_STATUS,
    CURRENT,
    DISCRETE_SPAN,
    FAULT_INPUTS,
    HOLD_HI,
    HOLD_LO,
    INPUT_MV,
    INPUT_SPAN,
    LIVE_FAULTS,
    MAX_CHANNELS,
    MAX_LEN,
    PROTECTED_OFF,
    RESET_CAUSE,
    RETRY_N,
    RETRY_OFF,
    STATE,
    STICKY_FAULTS,
    TOTAL_MA,
    TRIPS,
    UPTIME_MS,
    VERSION,
    X_ADDRESS,
    X_DEVICE,
    X_FUNCTION,
    X_VALUE,
    is_assigned,
)

if False:  # typing only; MicroPython never imports typing (the block is compiled away)
    from firmware.board import Board
    from firmware.config import Config
    from firmware.net import Net

    Regs = dict[int, int]  # a register image: address -> 16-bit value


def _u16(v: int) -> int:
    v = int(v)
    return 0 if v < 0 else (0xFFFF if v > 0xFFFF else v)


def _u32(v: int) -> int:
    v = int(v)
    return 0 if v < 0 else (0xFFFFFFFF if v > 0xFFFFFFFF else v)

PROXY_TAG = b"PROXY "
PROXY_MAX = 107  # the longest PROXY v1 line, CRLF included


class Framer:
    """Bytes in, whole MBAP ADUs out; ``bad`` once the stream must be closed.

    ``proxied``: the connection comes through the emulator's link proxy, which sends one
    PROXY protocol line first (HAProxy's version 1: ``PROXY TCP4 SRC DST SPORT DPORT\r\n``);
    ``client_ip`` is then the client's own address, the one the allow-list checks. Without
    that line (or with a malformed one) the connection is closed before any request."""

    def __init__(self, proxied: bool = False) -> None:
        self.buf = b""
        self.bad = False
        self.proxied = proxied
        self.client_ip: "str | None" = None

    def feed(self, data: bytes) -> None:
        self.buf += data

    def _proxy_line(self) -> bool:
        """Take the PROXY line off the front; False while it is still incomplete."""
        end = self.buf.find(b"\r\n")
        if end < 0:
            if len(self.buf) > PROXY_MAX or not PROXY_TAG.startswith(self.buf[:6]):
                self.bad = True
            return False
        parts = bytes(self.buf[:end]).split(b" ")
        self.buf = self.buf[end + 2:]
        self.client_ip = ""
        if parts[:2] == [b"PROXY", b"UNKNOWN"]:
            return True
        if len(parts) != 6 or parts[:2] != [b"PROXY", b"TCP4"]:
            self.bad = True
            return False
        try:
            self.client_ip = settings.int_to_ip(settings.ip_to_int(parts[2].decode()))
        except (ValueError, UnicodeError):
            self.bad = True
            return False
        return True

    def next(self) -> "bytes | None":
        if self.proxied and self.client_ip is None and not self.bad and not self._proxy_line():
            return None
        buf = self.buf
        if self.bad or len(buf) < 7:
            return None
        proto, length = struct.unpack_from(">HH", buf, 2)
        if proto != 0 or length > MAX_LEN or length < 2:
            self.bad = True
            self.buf = b""
            return None
        end = 6 + length
        if len(buf) < end:
            return None
        self.buf = buf[end:]
        return buf[:end]


def peer_ip(peer: object) -> str:
    """The dotted IPv4 address of a peer as the socket layer reports it: CPython's
    ``(host, port)``, or MicroPython's raw ``struct sockaddr_in`` (family, port, address
    bytes); "" for anything else (nothing on the allow-list matches it)."""
    if isinstance(peer, (tuple, list)):
        return str(peer[0]) if peer and isinstance(peer[0], str) else ""
    if isinstance(peer, (bytes, bytearray)) and len(peer) >= 8 \
            and ((peer[0] == 2 and peer[1] == 0) or (peer[0] == 0 and peer[1] == 2)):
        return "%d.%d.%d.%d" % (peer[4], peer[5], peer[6], peer[7])
    return ""


# --- register images ---------------------------------------------------------------------


def _input_regs(board: "Board") -> "list[int]":
    regs = [0] * INPUT_SPAN
    (mv, total, uptime, cause, cfg_status, flags), chans = board.status()
    for k in range(min(len(chans), MAX_CHANNELS)):
        c = chans[k]
        regs[CURRENT + k] = _u16(c[3])
        regs[STATE + k] = c[2]
        regs[LIVE_FAULTS + k] = c[4] & 0xFFFF
        regs[STICKY_FAULTS + k] = c[5] & 0xFFFF
        regs[TRIPS + k] = _u16(c[6])
    regs[INPUT_MV] = _u16(mv)
    _put(regs, TOTAL_MA, 2, total)
    _put(regs, UPTIME_MS, 2, uptime)
    regs[BOARD_FLAGS] = flags & 0xFFFF
    regs[RESET_CAUSE] = cause
    regs[CONFIG_STATUS] = cfg_status
    regs[CHANNEL_COUNT] = board.n
    regs[VERSION] = PROTOCOL_VERSION
    _put(regs, BOOT_ID, 2, board.boot_id)
    return regs


def _put(regs: "Regs | list[int]", addr: int, words: int, value: int) -> None:
    if words == 2:
        v = _u32(value)
        regs[addr] = v >> 16
        regs[addr + 1] = v & 0xFFFF
    else:
        regs[addr] = _u16(value)


def _get(regs: "Regs", addr: int, words: int) -> int:
    if words == 2:
        return (regs[addr] << 16) | regs[addr + 1]
    return regs[addr]


def _channel_regs(cfg: "Config", base: int, regs: "Regs") -> None:
    for name, off, words in CH_REGS:
        _put(regs, base + off, words, cfg[name])
    retry = cfg["retry_ms"]
    for i in range(RETRY_N):
        regs[base + RETRY_OFF + i] = _u16(retry[i]) if i < len(retry) else 0


def _board_regs(cfg: "Config", regs: "Regs") -> None:
    for name, addr, words in BOARD_REGS:
        _put(regs, addr, words, cfg[name])
    regs[CMD_REG] = 0


def _holding(board: "Board", lo: int, hi: int) -> "Regs":
    """Register image of the holding table for ``lo <= addr < hi`` (at least)."""
    regs: "Regs" = {}
    if lo < CH_BASE:
        _board_regs(board.cfg["board"], regs)
    n = board.n
    for k in range(MAX_CHANNELS):
        base = CH_BASE + CH_STRIDE * k
        if base + CH_STRIDE <= lo or base >= hi or k >= n:
            continue
        _channel_regs(board.cfg["channels"][k], base, regs)
    return regs


# --- requests ----------------------------------------------------------------------------


def _allowed(board: "Board", client_ip: str) -> bool:
    b = board.cfg["board"]
    return bool(b.get("modbus_write")) and client_ip in b.get("modbus_allow", [])


def _bits(values: "list[int]") -> bytes:
    out = bytearray((len(values) + 7) // 8)
    for i in range(len(values)):
        if values[i]:
            out[i >> 3] |= 1 << (i & 7)
    return bytes([len(out)]) + bytes(out)


def _words(values: "list[int]") -> bytes:
    return bytes([2 * len(values)]) + struct.pack(">%dH" % len(values), *values)


def _read(board: "Board", fc: int, addr: int, count: int) -> "bytes | int":
    if fc == 1 or fc == 2:
        if not 1 <= count <= 2000:
            return X_VALUE
        span = COIL_SPAN if fc == 1 else DISCRETE_SPAN
        if addr + count > span:
            return X_ADDRESS
        chans = board.channels
        n = len(chans)
        vals = []
        for a in range(addr, addr + count):
            k = a % MAX_CHANNELS
            if k >= n:
                vals.append(0)
            elif fc == 1:
                vals.append(chans[k].commanded)
            elif a < FAULT_INPUTS:
                vals.append(chans[k].physical)
            else:
                vals.append(chans[k].live & ~NOT_FAULTS != 0)  # not F_LOW: no fault
        return _bits(vals)
    if not 1 <= count <= 125:
        return X_VALUE
    if fc == 4:
        if addr + count > INPUT_SPAN:
            return X_ADDRESS
        return _words(_input_regs(board)[addr:addr + count])
    if addr < HOLD_LO or addr + count > HOLD_HI:
        return X_ADDRESS
    regs = _holding(board, addr, addr + count)
    return _words([regs.get(a, 0) for a in range(addr, addr + count)])


def _write_coils(board: "Board", addr: int, values: "list[int]") -> int:
    """Every coil is checked before any switch moves: a refusal changes nothing (FC15 too)."""
    n = board.n
    if addr + len(values) > COIL_SPAN or addr + len(values) > n:
        return X_ADDRESS
    for i in range(len(values)):
        err = board.check_switch(addr + i, bool(values[i]), False)
        if err == E_BAD_CHANNEL:
            return X_ADDRESS
        if err:
            return X_DEVICE
    for i in range(len(values)):
        if board.switch(addr + i, bool(values[i]), False)[0]:
            return X_DEVICE
    return 0


def _write_regs(board: "Board", addr: int, values: "list[int]") -> int:
    end = addr + len(values)
    if addr < HOLD_LO or end > HOLD_HI:
        return X_ADDRESS
    n = board.n
    regs = _holding(board, addr, end)
    for i in range(len(values)):
        a = addr + i
        if not is_assigned(a) or (a >= CH_BASE and (a - CH_BASE) // CH_STRIDE >= n):
            return X_ADDRESS
        if a >= CH_BASE and (a - CH_BASE) % CH_STRIDE == PROTECTED_OFF and values[i] != regs[a]:
            return X_ADDRESS  # protected: never writable over Modbus
        regs[a] = values[i]
    save = CMD_REG in regs and addr <= CMD_REG < end
    if save and regs[CMD_REG] != CMD_SAVE:
        return X_VALUE
    # decode and check everything before applying anything
    board_fields = None
    if addr < BOARD_REGS_END:
        board_fields = {}
        for name, a, words in BOARD_REGS:
            board_fields[name] = _get(regs, a, words)
        if settings.check_board(board_fields) is not None:
            return X_VALUE
    updates = []
    for k in range(min(n, MAX_CHANNELS)):
        base = CH_BASE + CH_STRIDE * k
        if base + CH_STRIDE <= addr or base >= end:
            continue
        fields: "Config" = {}
        for name, off, words in CH_REGS:
            v = _get(regs, base + off, words)
            if name == "powerup" or name == "protected":
                if v > 1:
                    return X_VALUE
                v = bool(v)
            fields[name] = v
        retry = []
        for i in range(RETRY_N):
            v = regs[base + RETRY_OFF + i]
            if v:
                retry.append(v)
        fields["retry_ms"] = retry
        if settings.check_channel(fields) is not None:
            return X_VALUE
        updates.append((k, fields))
    if board_fields is not None and board.set_board_config(board_fields):
        return X_VALUE
    for k, fields in updates:
        if board.set_channel_config(k, fields):
            return X_VALUE
    if save and board.save_config():
        return X_DEVICE
    return 0


def handle_pdu(board: "Board", pdu: bytes, client_ip: str) -> bytes:
    """The response PDU to one request PDU (function code first)."""
    fc = pdu[0]
    body = pdu[1:]
    if fc in (1, 2, 3, 4):
        if len(body) != 4:
            return bytes([fc | 0x80, X_VALUE])
        addr, count = struct.unpack(">HH", body)
        got = _read(board, fc, addr, count)
        if isinstance(got, int):
            return bytes([fc | 0x80, got])
        return bytes([fc]) + got
    if fc not in (5, 6, 15, 16):
        return bytes([fc | 0x80, X_FUNCTION])
    if not _allowed(board, client_ip):
        return bytes([fc | 0x80, X_FUNCTION])
    if fc == 5 or fc == 6:
        if len(body) != 4:
            return bytes([fc | 0x80, X_VALUE])
        addr, value = struct.unpack(">HH", body)
        if fc == 5:
            if value not in (0, 0xFF00):
                return bytes([fc | 0x80, X_VALUE])
            err = _write_coils(board, addr, [value == 0xFF00])
        else:
            err = _write_regs(board, addr, [value])
        if err:
            return bytes([fc | 0x80, err])
        return pdu
    if len(body) < 5:
        return bytes([fc | 0x80, X_VALUE])
    addr, count, nbytes = struct.unpack_from(">HHB", body)
    data = body[5:]
    if fc == 15:
        if not 1 <= count <= 1968 or nbytes != (count + 7) // 8 or len(data) != nbytes:
            return bytes([fc | 0x80, X_VALUE])
        err = _write_coils(board, addr, [(data[i >> 3] >> (i & 7)) & 1 for i in range(count)])
    else:
        if not 1 <= count <= 123 or nbytes != 2 * count or len(data) != nbytes:
            return bytes([fc | 0x80, X_VALUE])
        err = _write_regs(board, addr, list(struct.unpack(">%dH" % count, data)))
    if err:
        return bytes([fc | 0x80, err])
    return bytes([fc]) + struct.pack(">HH", addr, count)


def handle(board: "Board", adu: bytes, client_ip: str) -> bytes:
    """The response ADU to one request ADU (as cut by ``Framer``)."""
    tid, _, _, unit = struct.unpack_from(">HHHB", adu)
    try:
        pdu = handle_pdu(board, adu[7:], client_ip)
    except (ValueError, TypeError, KeyError, IndexError):
        pdu = bytes([adu[7] | 0x80, X_DEVICE])
    if pdu and pdu[0] & 0x80 == 0 and pdu[0] in (5, 6, 15, 16):
        board.host_seen(board.now)
    return struct.pack(">HHHB", tid, 0, len(pdu) + 1, unit) + pdu


# --- asyncio wrapper ---------------------------------------------------------------------


async def serve(net: "Net", host: str = "0.0.0.0", port: int = 502,
                proxied: bool = False) -> "asyncio.Server":
    """Serve Modbus TCP for ``net.app.board`` (a ``firmware.net.Net``); ``proxied``: every
    connection starts with a PROXY line naming the client (see ``Framer``)."""

    async def client(reader: "asyncio.StreamReader", writer: "asyncio.StreamWriter") -> None:
        if net.halted:  # held in reset: nobody is served
            await _close(writer)
            return
        links = net.links  # closed by a reset (Net.close_all)
        link = (writer, asyncio.current_task())
        links.append(link)
        framer = Framer(proxied)
        ip = peer_ip(writer.get_extra_info("peername"))
        timeout = net.read_timeout_ms / 1000
        try:
            while not net.halted:
                try:
                    data = await asyncio.wait_for(reader.read(512), timeout)
                except asyncio.TimeoutError:  # noqa: UP041 (MicroPython has no builtin TimeoutError)
                    break
                if not data or net.halted:
                    break
                framer.feed(data)
                while True:
                    adu = framer.next()
                    if adu is None:
                        break
                    who = framer.client_ip if proxied else ip
                    writer.write(handle(net.app.board, adu, who or ""))
                    await writer.drain()
                if framer.bad:
                    break
                await asyncio.sleep(0)
        except (OSError, asyncio.CancelledError):
            pass  # the peer went away, or a reset of the board closed the stream
        finally:
            if link in links:
                links.remove(link)
        await _close(writer)

    return await asyncio.start_server(client, host, port)


async def _close(writer: "asyncio.StreamWriter") -> None:
    try:
        writer.close()
        await writer.wait_closed()
    except OSError:
        pass


__all__ = ["Framer", "handle", "handle_pdu", "peer_ip", "serve"]
