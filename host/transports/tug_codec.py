"""The original TEDUSAR power board's wire format, sans I/O: frames in, frames out.

Every frame is a 4-byte header and a payload::

    +------+---------+--------+---------+
    | 0x02 | command | length | payload |
    +------+---------+--------+---------+
      u8      u8       u16      length bytes

Commands: 0 SPECIFICATIONS (u8 n, then n x {f32 max current A, f32 max voltage V}), 1 SET
FREQUENCY (u8 Hz, 0 stops the broadcast), 2 MEASUREMENTS (u8 n, then n x {u8 status, f32
current A, f32 voltage V}), 3 REQUEST (u8 the command wanted: 0 or 2), 4 CHANNEL (u8 channel,
u8 state 0/1), 5 ACK (u8 the command acknowledged, u8 result: 0 done, else refused).

What we assumed, since the original documents only the layout: integers and floats are
little-endian (the board's microcontroller wrote packed C structs), ``length`` counts the
payload only, the REQUEST and ACK payloads are as above, and the measurement ``status`` has bit
0 = switched on and bit 1 = fault (tripped or latched). There is no checksum: a frame with an
unknown command or a wrong length for its command is reported as bad and the decoder moves one
byte on to find the next 0x02. ``Decoder.feed``/``next`` follow ``protocol.framing``: partial
input is "need more data", the buffer is capped, nothing raises on bytes from the wire.
"""

from __future__ import annotations

import struct
from dataclasses import dataclass

START = 0x02
SPECS, SET_FREQ, MEASUREMENTS, REQUEST, CHANNEL, ACK = range(6)
HEADER = struct.Struct("<BBH")
SPEC = struct.Struct("<ff")
MEAS = struct.Struct("<Bff")
MAX_PAYLOAD = 1 + 255 * MEAS.size
BUFFER_CAP = 8 * (HEADER.size + MAX_PAYLOAD)
STATUS_ON = 0x01
STATUS_FAULT = 0x02


@dataclass(frozen=True)
class TugFrame:
    command: int
    payload: bytes


@dataclass(frozen=True)
class TugBad:
    reason: str
    skipped: int


def encode(command: int, payload: bytes = b"") -> bytes:
    return HEADER.pack(START, command, len(payload)) + payload


def specs(channels: list[tuple[float, float]]) -> bytes:
    return encode(SPECS, bytes([len(channels)]) + b"".join(SPEC.pack(*c) for c in channels))


def measurements(channels: list[tuple[int, float, float]]) -> bytes:
    return encode(MEASUREMENTS,
                  bytes([len(channels)]) + b"".join(MEAS.pack(*c) for c in channels))


def request(command: int) -> bytes:
    return encode(REQUEST, bytes([command]))


def set_frequency(hz: int) -> bytes:
    return encode(SET_FREQ, bytes([hz]))


def channel(ch: int, on: bool) -> bytes:
    return encode(CHANNEL, bytes([ch, 1 if on else 0]))


def ack(command: int, result: int = 0) -> bytes:
    return encode(ACK, bytes([command, result]))


def parse_specs(payload: bytes) -> list[tuple[float, float]]:
    return [SPEC.unpack_from(payload, 1 + i * SPEC.size) for i in range(payload[0])]


def parse_measurements(payload: bytes) -> list[tuple[int, float, float]]:
    return [MEAS.unpack_from(payload, 1 + i * MEAS.size) for i in range(payload[0])]


def _length_ok(command: int, payload: bytes) -> bool:
    n = len(payload)
    if command == SPECS:
        return n >= 1 and n == 1 + payload[0] * SPEC.size
    if command == MEASUREMENTS:
        return n >= 1 and n == 1 + payload[0] * MEAS.size
    return n == {SET_FREQ: 1, REQUEST: 1, CHANNEL: 2, ACK: 2}.get(command, -1)


class Decoder:
    """Bytes in, ``TugFrame`` or ``TugBad`` out (see the module docstring)."""

    def __init__(self) -> None:
        self._buf = bytearray()

    def feed(self, data: bytes) -> None:
        self._buf.extend(data)
        if len(self._buf) > BUFFER_CAP:  # a flood without frames: keep the tail
            del self._buf[: len(self._buf) - BUFFER_CAP]

    def next(self) -> TugFrame | TugBad | None:
        buf = self._buf
        if not buf:
            return None
        if buf[0] != START:
            i = buf.find(bytes([START]))
            skipped = len(buf) if i < 0 else i
            del buf[:skipped]
            return TugBad("bytes outside a frame", skipped)
        if len(buf) < HEADER.size:
            return None
        _, command, length = HEADER.unpack_from(buf)
        if command > ACK or length > MAX_PAYLOAD:
            del buf[:1]
            return TugBad(f"bad header (command {command}, length {length})", 1)
        end = HEADER.size + length
        if len(buf) < end:
            return None
        payload = bytes(buf[HEADER.size:end])
        if not _length_ok(command, payload):
            del buf[:1]
            return TugBad(f"command {command} with a payload of {length} bytes", 1)
        del buf[:end]
        return TugFrame(command, payload)

    def frames(self) -> list[TugFrame | TugBad]:
        out: list[TugFrame | TugBad] = []
        while (item := self.next()) is not None:
            out.append(item)
        return out
