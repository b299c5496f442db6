"""A host written from PROTOCOL.md alone: an independent peer for the native front ends.

It imports nothing of ``protocol/``, ``firmware/`` or ``host/``: framing (§2: marker 0xDB 0x58,
version 1, type, req_id, length, payload, CRC-32 over version..payload, big-endian), the
handshake (§3), the messages it needs (§4: HELLO, HELLO_REQUEST, PING/PONG, GET_STATE/STATE,
SUBSCRIBE/ACK with its optional per_frame, MEASUREMENT, MEASUREMENT_BATCH, EVENT,
SWITCH/SWITCHED, ERROR) and authentication (§5: counter u32
and the first 16 bytes of HMAC-SHA256(key, nonce ‖ frame from the marker through the
counter)) are written out here from the text, with the standard library only. ``SpecPeer``
runs over any pair of byte functions (``send(bytes)``, ``recv(timeout) -> bytes``), so the
same peer talks to a TCP socket and to a serial port.
"""

from __future__ import annotations

import hashlib
import hmac
import struct
import time
import zlib
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

MARKER = b"\xdb\x58"
VERSION = 1
HELLO, HELLO_REQUEST, PING, PONG = 0x01, 0x02, 0x03, 0x04
GET_STATE, STATE, SUBSCRIBE, MEASUREMENT, EVENT = 0x10, 0x11, 0x12, 0x13, 0x14
MEASUREMENT_BATCH = 0x15
CAP_BATCH = 0x0080  # §10: SUBSCRIBE takes per_frame
SWITCH, SWITCHED = 0x20, 0x21
ACK, ERROR = 0x7E, 0x7F
PUSHES = (MEASUREMENT, MEASUREMENT_BATCH, EVENT)  # req_id 0: never a reply


def frame(type_: int, req_id: int, payload: bytes) -> bytes:
    body = struct.pack(">BBHH", VERSION, type_, req_id, len(payload)) + payload
    return MARKER + body + struct.pack(">I", zlib.crc32(body) & 0xFFFFFFFF)


@dataclass
class Frame:
    type: int
    req_id: int
    payload: bytes


@dataclass
class Decoder:
    """§2's receiver: find the marker, check length and CRC, resynchronise after damage."""

    buf: bytearray = field(default_factory=bytearray)

    def feed(self, data: bytes) -> list[Frame]:
        self.buf += data
        out = []
        while True:
            i = self.buf.find(MARKER)
            if i < 0:
                del self.buf[:max(0, len(self.buf) - 1)]
                return out
            del self.buf[:i]
            if len(self.buf) < 8:
                return out
            _ver, type_, req_id, length = struct.unpack_from(">BBHH", self.buf, 2)
            if length > 1024:
                del self.buf[:1]
                continue
            end = 8 + length + 4
            if len(self.buf) < end:
                return out
            (crc,) = struct.unpack_from(">I", self.buf, end - 4)
            if zlib.crc32(bytes(self.buf[2:end - 4])) & 0xFFFFFFFF != crc:
                del self.buf[:1]
                continue
            out.append(Frame(type_, req_id, bytes(self.buf[8:end - 4])))
            del self.buf[:end]


def _str(p: bytes, i: int) -> tuple[str, int]:
    n = p[i]
    return p[i + 1:i + 1 + n].decode(), i + 1 + n


def parse_hello(p: bytes) -> dict[str, Any]:
    version = p[0]
    board_id, i = _str(p, 1)
    firmware, i = _str(p, i)
    channels, caps, boot_id = struct.unpack_from(">BHI", p, i)
    i += 7
    nonce = p[i:i + 16]
    reset_cause, config_status = p[i + 16], p[i + 17]
    return {"version": version, "board_id": board_id, "firmware": firmware,
            "channels": channels, "capabilities": caps, "boot_id": boot_id, "nonce": nonce,
            "reset_cause": reset_cause, "config_status": config_status}


def parse_state(p: bytes) -> dict[str, Any]:
    uptime, mv, total, cause, cfg, flags, n = struct.unpack_from(">IHiBBHB", p, 0)
    chans = []
    for k in range(n):
        ch, cmd, phys, st, ma, live, sticky, trips, retries = struct.unpack_from(
            ">BBBBiHHHB", p, 15 + 15 * k)
        chans.append({"channel": ch, "commanded": cmd == 1, "physical": phys == 1,
                      "state": st, "current_ma": ma, "live_faults": live,
                      "sticky_faults": sticky, "trips": trips, "retries": retries})
    return {"uptime_ms": uptime, "input_mv": mv, "total_ma": total, "reset_cause": cause,
            "config_status": cfg, "board_flags": flags, "channels": chans}


def parse_measurement(p: bytes) -> dict[str, Any]:
    seq, uptime, mv, on, faults, n = struct.unpack_from(">IIHHHB", p, 0)
    currents = list(struct.unpack_from(f">{n}i", p, 15))
    return {"seq": seq, "uptime_ms": uptime, "input_mv": mv, "on_mask": on,
            "fault_mask": faults, "currents_ma": currents}


def parse_batch(p: bytes) -> list[dict[str, Any]]:
    """§4.2 MEASUREMENT_BATCH: count u8, channels u8, then count readings of 14 + 4 x channels
    bytes, read with one format; ValueError for anything §4.2 calls malformed."""
    if len(p) < 2:
        raise ValueError("MEASUREMENT_BATCH shorter than its header")
    count, channels = p[0], p[1]
    if not 1 <= count <= 10:
        raise ValueError(f"MEASUREMENT_BATCH count {count} is not 1-10")
    size = 14 + 4 * channels
    if len(p) != 2 + count * size:
        raise ValueError(f"MEASUREMENT_BATCH of {count} x {size} bytes in {len(p) - 2}")
    v = struct.unpack(">" + f"IIHHH{channels}i" * count, p[2:])
    step = 5 + channels
    return [{"seq": v[i], "uptime_ms": v[i + 1], "input_mv": v[i + 2], "on_mask": v[i + 3],
             "fault_mask": v[i + 4], "currents_ma": list(v[i + 5:i + step])}
            for i in range(0, len(v), step)]


def parse_error(p: bytes) -> dict[str, Any]:
    code, of_type = struct.unpack_from(">HB", p, 0)
    text, _ = _str(p, 3)
    return {"code": code, "of_type": of_type, "text": text}


class SpecPeer:
    """One host session over ``send``/``recv`` byte functions, from PROTOCOL.md only."""

    def __init__(self, send: Callable[[bytes], None], recv: Callable[[float], bytes],
                 key: bytes | None = None) -> None:
        self._send = send
        self._recv = recv
        self.key = key
        self.decoder = Decoder()
        self.backlog: list[Frame] = []
        self.req = 0
        self.counter = 0
        self.hello: dict[str, Any] | None = None

    def next_id(self) -> int:
        self.req = self.req % 0xFFFF + 1
        return self.req

    def wait(self, pred: Callable[[Frame], bool], timeout: float = 5.0) -> Frame:
        end = time.monotonic() + timeout
        while True:
            for i, f in enumerate(self.backlog):
                if pred(f):
                    return self.backlog.pop(i)
            left = end - time.monotonic()
            if left <= 0:
                raise AssertionError(f"no matching frame within {timeout} s: {self.backlog}")
            self.backlog += self.decoder.feed(self._recv(min(left, 0.2)))

    def greet(self, ask: bool, timeout: float = 5.0) -> dict[str, Any]:
        """The session's HELLO: the one sent on connect, or (``ask``) a HELLO_REQUEST's."""
        if ask:
            rid = self.next_id()
            self._send(frame(HELLO_REQUEST, rid, b""))
            got = self.wait(lambda f: f.type == HELLO and f.req_id == rid, timeout)
        else:
            got = self.wait(lambda f: f.type == HELLO, timeout)
        self.backlog = [f for f in self.backlog if f.type != HELLO]
        self.hello = parse_hello(got.payload)
        self.counter = 0
        return self.hello

    def request(self, type_: int, payload: bytes = b"", timeout: float = 5.0) -> Frame:
        rid = self.next_id()
        self._send(frame(type_, rid, payload))
        return self.wait(lambda f: f.req_id == rid and f.type not in PUSHES, timeout)

    def signed(self, type_: int, payload: bytes, timeout: float = 5.0) -> Frame:
        """An authenticated request (§5); needs ``key`` and a session's nonce."""
        assert self.key is not None and self.hello is not None
        self.counter += 1
        rid = self.next_id()
        body = payload + struct.pack(">I", self.counter)
        head = MARKER + struct.pack(">BBHH", VERSION, type_, rid, len(body) + 16)
        tag = hmac.new(self.key, self.hello["nonce"] + head + body,
                       hashlib.sha256).digest()[:16]
        whole = head + body + tag
        self._send(whole + struct.pack(">I", zlib.crc32(whole[2:]) & 0xFFFFFFFF))
        return self.wait(lambda f: f.req_id == rid, timeout)

    def ping(self, token: int) -> tuple[int, int]:
        got = self.request(PING, struct.pack(">I", token))
        assert got.type == PONG, got
        tok, uptime = struct.unpack(">II", got.payload)
        return tok, uptime

    def state(self) -> dict[str, Any]:
        got = self.request(GET_STATE)
        assert got.type == STATE, got
        return parse_state(got.payload)

    def subscribe(self, rate_hz: int, per_frame: int | None = None) -> Frame:
        """SUBSCRIBE; ``per_frame`` (§4.2) is sent as the optional second byte when given."""
        extra = b"" if per_frame is None else bytes([per_frame])
        return self.request(SUBSCRIBE, bytes([rate_hz]) + extra)

    def switch(self, channel: int, on: bool, force: bool = False) -> Frame:
        return self.signed(SWITCH, bytes([channel, int(on), int(force)]))

    def measurements(self, n: int, timeout: float = 10.0) -> list[dict[str, Any]]:
        """At least ``n`` readings, from MEASUREMENT or MEASUREMENT_BATCH frames, in order."""
        out: list[dict[str, Any]] = []
        while len(out) < n:
            got = self.wait(lambda f: f.type in (MEASUREMENT, MEASUREMENT_BATCH), timeout)
            if got.type == MEASUREMENT:
                out.append(parse_measurement(got.payload))
            else:
                out += parse_batch(got.payload)
        return out
