"""The original TEDUSAR power board's wire format (``tug://``), sans I/O, for board and host.

Theory of operation. The format is the one of ``tug_ist_diagnosis_board`` (Board.cpp,
Message.cpp, Controller.cpp; PROTOCOL.md "The original TEDUSAR format"). Every frame is::

    +------+---------+--------+---------+
    | 0x02 | command | length | payload |
    +------+---------+--------+---------+
      u8      u8      u16 LE    length bytes

There is no checksum; integers and floats are little-endian (the original packed them by
pointer casts on x86). Commands, with who sends them and their payload:

    0 SPECIFICATIONS  board  u8 n, then n x {f32 max current A, f32 max voltage V}
    1 SET FREQUENCY   host   u8 rate (Hz; the original board ignores it)
    2 MEASUREMENTS    board  u8 n, then n x {u8 status 0 off / 1 on, f32 current A, f32 V}
    3 REQUEST         host   nothing (the original host adds one stray byte after the frame)
    4 CHANNEL         host   u8 channel, u8 state (0 off, 1 on)
    5 ACK             board  u8 error code (0 done; the original board only ever sends 0)

``Decoder(FROM_HOST)`` (the board's side) and ``Decoder(FROM_BOARD)`` (the host's) accept
only the commands the peer sends, each with its exact length (REQUEST: 0, or 1 as earlier
dxboard clients sent it); SPECIFICATIONS and MEASUREMENTS must agree with their count byte.
A header is judged as soon as its bytes arrive: a wrong command or length is dropped by
moving one byte on and looking for the next 0x02 (``Bad``, ``skipped`` 1), bytes outside a
frame are one ``Bad`` per run. So the original REQUEST's stray byte is harmless: anything but
0x02 is skipped, and a stray 0x02 followed by the next frame reads as the header ``02 02``,
MEASUREMENTS, which a host never sends: one byte is dropped and that frame decodes. A CHANNEL
frame cut short and followed by a new frame always reads a state byte of 2 (the new frame's
0x02) or a wrong length, so it can never switch anything. Partial input is "need more data"
(``next`` returns None); the buffer is capped (``BUFFER_CAP``: the oldest bytes are dropped
and reported as ``Bad``); nothing here raises on bytes from the wire. The frame builders take
values from our own code (``LocalProtocolError`` on a value that does not fit).
"""

import struct

from protocol.compat import const
from protocol.constants import E_BAD_CHANNEL, E_BAD_VALUE, E_INHIBITED, E_LATCHED, E_PROTECTED
from protocol.errors import LocalProtocolError

START = const(0x02)
SPECS = const(0)
SET_FREQ = const(1)
MEASUREMENTS = const(2)
REQUEST = const(3)
CHANNEL = const(4)
ACK = const(5)
FROM_HOST = (SET_FREQ, REQUEST, CHANNEL)
FROM_BOARD = (SPECS, MEASUREMENTS, ACK)

HEADER_LEN = const(4)
SPEC_LEN = const(8)
MEAS_LEN = const(9)
# The original host reads only the low byte of ``length`` (Controller.cpp 140): a
# MEASUREMENTS frame must stay below 256 bytes of payload, so 28 channels at most.
MAX_CHANNELS = const(28)
MAX_PAYLOAD = 1 + 255 * MEAS_LEN
BUFFER_CAP = const(4096)
BROADCAST_MS = const(1000)  # the original broadcasts once a second, whatever rate is asked

STATUS_OFF = const(0)
STATUS_ON = const(1)

# ACK error codes (PROTOCOL.md): 0 done; the rest are ours, the original never refuses.
ACK_OK = const(0)
ACK_READ_ONLY = const(1)  # this front end was not started with switching allowed
ACK_BAD_CHANNEL = const(2)  # no such channel
ACK_BAD_STATE = const(3)  # a state byte other than 0 or 1
ACK_PROTECTED = const(4)  # a protected channel is never switched off from here
ACK_LATCHED = const(5)  # latched off by protection: only a native CLEAR releases it
ACK_REFUSED = const(6)  # any other refusal of the board (inhibited, switch fault)
ACK_TEXT = {
    ACK_OK: "done",
    ACK_READ_ONLY: "switching over tug is not enabled on this board",
    ACK_BAD_CHANNEL: "no such channel",
    ACK_BAD_STATE: "the state must be 0 or 1",
    ACK_PROTECTED: "protected channels are not switched off over tug",
    ACK_LATCHED: "the channel is latched off; clear it over the native protocol",
    ACK_REFUSED: "the board refused",
}
# (ACK code, E_* code): the board's refusal and the error the host reports for it
_ACK_ERRORS = ((ACK_READ_ONLY, E_INHIBITED), (ACK_BAD_CHANNEL, E_BAD_CHANNEL),
               (ACK_BAD_STATE, E_BAD_VALUE), (ACK_PROTECTED, E_PROTECTED),
               (ACK_LATCHED, E_LATCHED), (ACK_REFUSED, E_INHIBITED))


def ack_code(error: int) -> int:
    """The ACK byte for a board command's result (0 or an ``E_*`` code)."""
    if not error:
        return ACK_OK
    for code, err in _ACK_ERRORS[1:]:
        if err == error:
            return code
    return ACK_REFUSED


def error_of(code: int) -> int:
    """The ``E_*`` code a host reports for a refusing ACK byte (0 for done)."""
    if code == ACK_OK:
        return 0
    for ack_, err in _ACK_ERRORS:
        if ack_ == code:
            return err
    return E_INHIBITED


class Frame:
    """A whole, well-formed frame from the peer."""

    def __init__(self, command: int, payload: bytes) -> None:
        self.command = command
        self.payload = payload

    def __eq__(self, other: object) -> bool:
        return isinstance(other, Frame) and (other.command, other.payload) == (
            self.command, self.payload)

    def __repr__(self) -> str:
        return "Frame(%d, %r)" % (self.command, self.payload)


class Bad:
    """Bytes that are not a frame: ``skipped`` of them were dropped."""

    def __init__(self, reason: str, skipped: int) -> None:
        self.reason = reason
        self.skipped = skipped

    def __repr__(self) -> str:
        return "Bad(%r, %d)" % (self.reason, self.skipped)


# --- frames out ---------------------------------------------------------------------------

def encode(command: int, payload: bytes = b"") -> bytes:
    if not 0 <= command <= 0xFF or len(payload) > 0xFFFF:
        raise LocalProtocolError("tug frame out of range")
    return struct.pack("<BBH", START, command, len(payload)) + payload


def _byte(value: int, what: str) -> bytes:
    if not 0 <= value <= 0xFF:
        raise LocalProtocolError("%s %d does not fit a byte" % (what, value))
    return bytes([value])


def specs(channels: list) -> bytes:  # type: ignore[type-arg]
    """SPECIFICATIONS of ``[(max_current_a, max_voltage_v), ...]``."""
    out = [_byte(len(channels), "channel count")]
    for amps, volts in channels:
        out.append(struct.pack("<ff", amps, volts))
    return encode(SPECS, b"".join(out))


def measurements(channels: list) -> bytes:  # type: ignore[type-arg]
    """MEASUREMENTS of ``[(status, current_a, voltage_v), ...]``."""
    out = [_byte(len(channels), "channel count")]
    for status, amps, volts in channels:
        out.append(struct.pack("<Bff", status, amps, volts))
    return encode(MEASUREMENTS, b"".join(out))


def set_frequency(hz: int) -> bytes:
    return encode(SET_FREQ, _byte(hz, "rate"))


def request() -> bytes:
    """REQUEST as the original host sends it, without the stray byte after it."""
    return encode(REQUEST)


def channel(ch: int, on: bool) -> bytes:
    return encode(CHANNEL, _byte(ch, "channel") + (b"\x01" if on else b"\x00"))


def ack(code: int = ACK_OK) -> bytes:
    return encode(ACK, _byte(code, "error code"))


def parse_specs(payload: bytes) -> list:  # type: ignore[type-arg]
    """``[(max_current_a, max_voltage_v), ...]`` of a decoded SPECIFICATIONS payload."""
    return [struct.unpack_from("<ff", payload, 1 + i * SPEC_LEN) for i in range(payload[0])]


def parse_measurements(payload: bytes) -> list:  # type: ignore[type-arg]
    """``[(status, current_a, voltage_v), ...]`` of a decoded MEASUREMENTS payload."""
    return [struct.unpack_from("<Bff", payload, 1 + i * MEAS_LEN) for i in range(payload[0])]


# --- frames in ----------------------------------------------------------------------------

def _length_ok(command: int, length: int) -> bool:
    if command == SPECS:
        return length >= 1 and (length - 1) % SPEC_LEN == 0 and length <= 1 + 255 * SPEC_LEN
    if command == MEASUREMENTS:
        return length >= 1 and (length - 1) % MEAS_LEN == 0 and length <= MAX_PAYLOAD
    if command == REQUEST:
        return length <= 1
    if command == CHANNEL:
        return length == 2
    return length == 1  # SET_FREQ, ACK


def _count_ok(command: int, length: int, count: int) -> bool:
    if command == SPECS:
        return length == 1 + count * SPEC_LEN
    if command == MEASUREMENTS:
        return length == 1 + count * MEAS_LEN
    return True


class TugDecoder:
    """Bytes in (``feed``), ``Frame`` or ``Bad`` out (``next``); see the module docstring."""

    def __init__(self, accept: tuple) -> None:  # type: ignore[type-arg]
        self.accept = accept
        self._buf = bytearray()
        self._pos = 0
        self._dropped = 0

    @property
    def pending(self) -> int:
        """Bytes received and not yet decoded."""
        return len(self._buf) - self._pos

    def feed(self, data: bytes) -> None:
        buf = self._buf[self._pos:] if self._pos else self._buf
        self._pos = 0
        buf.extend(data)
        over = len(buf) - BUFFER_CAP
        if over > 0:  # a flood that nobody drains: keep the newest bytes
            self._dropped += over
            buf = buf[over:]
        self._buf = buf

    def _bad(self, start: int, reason: str) -> Bad:
        self._pos = start + 1
        return Bad(reason, 1)

    def next(self) -> "Frame | Bad | None":
        """The next frame or ``Bad``, or None when more bytes are needed."""
        if self._dropped:
            n = self._dropped
            self._dropped = 0
            return Bad("receive buffer overflow", n)
        buf = self._buf
        start = self._pos
        n = len(buf)
        if start >= n:
            return None
        if buf[start] != START:
            i = buf.find(b"\x02", start)
            if i < 0:
                i = n
            self._pos = i
            return Bad("bytes outside a frame", i - start)
        if n - start < 2:
            return None
        command = buf[start + 1]
        if command not in self.accept:
            return self._bad(start, "command %d not expected here" % command)
        if n - start < HEADER_LEN:
            return None
        length = buf[start + 2] | buf[start + 3] << 8
        if not _length_ok(command, length):
            return self._bad(start, "command %d with length %d" % (command, length))
        if n - start > HEADER_LEN and not _count_ok(command, length, buf[start + HEADER_LEN]):
            return self._bad(start, "command %d: count and length disagree" % command)
        end = start + HEADER_LEN + length
        if n < end:
            return None
        self._pos = end
        return Frame(command, bytes(buf[start + HEADER_LEN:end]))

    def frames(self) -> list:  # type: ignore[type-arg]
        """Every event decodable now."""
        out = []
        ev = self.next()
        while ev is not None:
            out.append(ev)
            ev = self.next()
        return out
