"""The CAN layout of PROTOCOL.md §9, written once: identifiers, frame layouts, the command tag.

Classic CAN, 11-bit identifiers, 8 data bytes, Intel byte order (little-endian), as
``protocol/dxboard.dbc`` describes for CAN tools. N is the board's node number (0-15)::

    DXB_Status    0x100+N      UptimeS u32 | InputVoltage u16 mV | BoardFlags u8 |
                               ResetCause 4 bits, ConfigStatus 4 bits
    DXB_Currents  0x110+4N+g   channels 4g..4g+3: i16 each, in 10 mA
    DXB_Channel   0x140+16N+k  State 4 bits, Commanded 1, Physical 1 | Current i20 mA |
                               LiveFaults u16 | Trips u8 | Retries u8
    DXB_Cmd       0x180+N      Op u8 | Channel u8 | Force u8 (bit 0) | OffTime u8 (100 ms) |
                               Counter u32
    DXB_CmdTagA/B 0x181+N/0x182+N  tag bytes 0-7 / 8-15
    DXB_CmdResult 0x188+N      Op u8 | Channel u8 | Error u16 | State 4 bits, Physical 1 |
                               3 zero bytes
    DXB_Nonce     0x1F0+N      the 8 nonce bytes

The tag is the first 16 bytes of HMAC-SHA256(key, nonce ‖ cmd): ``nonce`` the 8 data bytes of
DXB_Nonce in the order they are on the bus (byte 0 first; never as an integer), ``cmd`` the 8
data bytes of DXB_Cmd as sent. Each ``*_frame`` packs the data bytes and each ``parse_*``
unpacks them (``ValueError`` if the data is not 8 bytes).
"""

import struct

from protocol.auth import hmac_sha256
from protocol.compat import const

FRAME_LEN = const(8)
ID_STATUS = const(0x100)
ID_CURRENTS = const(0x110)
ID_CHANNEL = const(0x140)
ID_CMD = const(0x180)
ID_TAG_A = const(0x181)
ID_TAG_B = const(0x182)
ID_RESULT = const(0x188)
ID_NONCE = const(0x1F0)
MAX_NODE = const(15)
MAX_CHANNELS = const(16)
CURRENT_GROUPS = const(3)
SLOW_MS = const(1000)  # DXB_Status, DXB_Nonce and every DXB_Channel: once a second
TAG_WINDOW_MS = const(100)  # DXB_CmdTagA and B must follow DXB_Cmd within this
OP_ON = const(1)
OP_OFF = const(2)
OP_CYCLE = const(3)
OP_CLEAR = const(4)
OPS = (OP_ON, OP_OFF, OP_CYCLE, OP_CLEAR)
CURRENT_MIN = const(-0x80000)  # i20
CURRENT_MAX = const(0x7FFFF)

_CMD = "<BBBBI"
_RESULT = "<BBHBBBB"


def _clamp(v: int, lo: int, hi: int) -> int:
    return lo if v < lo else (hi if v > hi else v)


def _eight(data: bytes) -> bytes:
    if len(data) != FRAME_LEN:
        raise ValueError("a CAN frame of this layout has 8 data bytes, not %d" % len(data))
    return data


# --- identifiers of node N -------------------------------------------------------------


def currents_id(node: int, g: int) -> int:
    return ID_CURRENTS + 4 * node + g


def channel_id(node: int, k: int) -> int:
    return ID_CHANNEL + 16 * node + k


# --- board -> bus -----------------------------------------------------------------------


def status_frame(board_status: tuple) -> bytes:  # type: ignore[type-arg]
    """DXB_Status from ``(input_mv, total_ma, uptime_ms, reset_cause, config_status, flags)``."""
    mv, _total, uptime, cause, cfg_status, flags = board_status
    return struct.pack("<IHBB", (uptime // 1000) & 0xFFFFFFFF, _clamp(mv, 0, 0xFFFF),
                       flags & 0xFF, (cause & 0xF) | ((cfg_status & 0xF) << 4))


def parse_status(data: bytes) -> tuple:  # type: ignore[type-arg]
    """``(uptime_s, input_mv, flags, reset_cause, config_status)``."""
    up, mv, flags, b7 = struct.unpack("<IHBB", _eight(data))
    return up, mv, flags, b7 & 0xF, b7 >> 4


def currents_frame(currents_ma: list, g: int) -> bytes:  # type: ignore[type-arg]
    """DXB_Currents_g: channels 4g..4g+3 rounded to 10 mA (missing channels 0)."""
    vals = []
    for i in range(4 * g, 4 * g + 4):
        ma = currents_ma[i] if i < len(currents_ma) else 0
        vals.append(_clamp((ma + 5) // 10 if ma >= 0 else -((-ma + 5) // 10), -32768, 32767))
    return struct.pack("<4h", *vals)


def parse_currents(data: bytes) -> list:  # type: ignore[type-arg]
    """The four currents of a DXB_Currents frame, in mA."""
    return [v * 10 for v in struct.unpack("<4h", _eight(data))]


def channel_frame(ch: tuple) -> bytes:  # type: ignore[type-arg]
    """DXB_Channel from a ``Board.channel_status`` tuple ``(commanded, physical, state,
    current_ma, live, sticky, trips, retries)``."""
    commanded, physical, state, ma, live, _sticky, trips, retries = ch
    ma = _clamp(ma, CURRENT_MIN, CURRENT_MAX) & 0xFFFFF
    b0 = (state & 0xF) | (0x10 if commanded else 0) | (0x20 if physical else 0)
    return struct.pack("<BBBBHBB", b0, ma & 0xFF, (ma >> 8) & 0xFF, ma >> 16, live & 0xFFFF,
                       _clamp(trips, 0, 255), _clamp(retries, 0, 255))


def parse_channel(data: bytes) -> tuple:  # type: ignore[type-arg]
    """``(state, commanded, physical, current_ma, live_faults, trips, retries)``."""
    b0, lo, mid, hi, live, trips, retries = struct.unpack("<BBBBHBB", _eight(data))
    ma = lo | mid << 8 | (hi & 0x0F) << 16
    if ma & 0x80000:
        ma -= 0x100000
    return b0 & 0xF, bool(b0 & 0x10), bool(b0 & 0x20), ma, live, trips, retries


def result_frame(op: int, ch: int, err: int, state: int, physical: bool) -> bytes:
    return struct.pack(_RESULT, op & 0xFF, ch & 0xFF, err, (state & 0xF) | (0x10 if physical
                                                                             else 0), 0, 0, 0)


def parse_result(data: bytes) -> tuple:  # type: ignore[type-arg]
    """``(op, channel, error, state, physical)``."""
    op, ch, err, b4, _a, _b, _c = struct.unpack(_RESULT, _eight(data))
    return op, ch, err, b4 & 0xF, bool(b4 & 0x10)


# --- bus -> board -----------------------------------------------------------------------


def command_frame(op: int, ch: int, force: bool = False, off_100ms: int = 0,
                  counter: int = 0) -> bytes:
    return struct.pack(_CMD, op, ch, 1 if force else 0, off_100ms, counter)


def parse_command(data: bytes) -> tuple:  # type: ignore[type-arg]
    """``(op, channel, force, off_100ms, counter)``."""
    op, ch, force, off, counter = struct.unpack(_CMD, _eight(data))
    return op, ch, bool(force & 1), off, counter


def command_tag(key: bytes, nonce: bytes, cmd: bytes) -> bytes:
    """The 16 bytes that DXB_CmdTagA (first 8) and DXB_CmdTagB (last 8) carry."""
    return hmac_sha256(key, bytes(nonce) + bytes(cmd))[:16]
