"""Frames on a byte stream: encoding, and a decoder that resynchronises after garbage.

Theory of operation. Every frame (PROTOCOL.md §2) is::

    +------+------+-----+------+--------+--------+---------+--------+
    | 0xDB | 0x58 | ver | type | req_id | length | payload | CRC-32 |
    +------+------+-----+------+--------+--------+---------+--------+
       1      1     1      1      2        2       length     4

with big-endian integers and the CRC-32 (IEEE) over ``ver`` through the payload. The
``Decoder`` keeps a capped buffer and a read position. ``next()`` looks for the start
marker: bytes before it are garbage, reported once per run as ``E_GARBAGE`` when the run
ends (at the next marker, at the end of the stream, or every ``MAX_FRAME`` bytes of a flood).
With a whole header it checks the length (``E_TOO_LARGE`` above ``MAX_PAYLOAD``); with the
whole frame it checks the CRC (``E_BAD_CRC``). A bad frame is dropped by moving one byte
past its start marker and searching again, so a frame that follows garbage or a damaged
frame is still found; the bytes skipped on the way count as that frame's damage, not as a
new garbage report. A frame that stays incomplete can be cut off with ``truncate()`` (end
of stream, or the caller's timeout): ``E_TRUNCATED``. The results do not depend on how
the bytes were split into chunks. Nothing here raises on bytes from the wire.
"""

import struct

from protocol.compat import crc32
from protocol.constants import (
    E_BAD_CRC,
    E_GARBAGE,
    E_TOO_LARGE,
    E_TRUNCATED,
    ERROR_TEXT,
    PROTOCOL_VERSION,
)
from protocol.errors import LocalProtocolError, RemoteProtocolError

MAGIC = b"\xdb\x58"
HEADER_LEN = 8
CRC_LEN = 4
MAX_PAYLOAD = 1024
MAX_FRAME = HEADER_LEN + MAX_PAYLOAD + CRC_LEN
BUFFER_CAP = 8 * MAX_FRAME  # bytes a caller may feed without draining events


class RawFrame:
    """A frame whose CRC checked out; ``raw`` is the whole frame, start marker to CRC."""

    def __init__(self, version: int, type: int, req_id: int, raw: bytes) -> None:
        self.version = version
        self.type = type
        self.req_id = req_id
        self.raw = raw

    @property
    def payload(self) -> bytes:
        return self.raw[HEADER_LEN:-CRC_LEN]


class BadFrame:
    """Bytes from the wire that are not a valid message: ``code`` is an E_* error code.

    ``req_id``, ``of_type`` and ``version`` are known (non-zero) only when the frame itself
    was intact (its CRC checked out); ``skipped`` counts the bytes thrown away.
    """

    def __init__(
        self,
        code: int,
        detail: str = "",
        req_id: int = 0,
        of_type: int = 0,
        version: int = 0,
        skipped: int = 0,
    ) -> None:
        self.code = code
        self.detail = detail
        self.req_id = req_id
        self.of_type = of_type
        self.version = version
        self.skipped = skipped

    @property
    def text(self) -> str:
        base = ERROR_TEXT.get(self.code, "error")
        return base + (": " + self.detail if self.detail else "")

    def error(self) -> RemoteProtocolError:
        return RemoteProtocolError(self.code, self.text)

    def __repr__(self) -> str:
        return "BadFrame(code=%d, text=%r, req_id=%d, of_type=%d, skipped=%d)" % (
            self.code,
            self.text,
            self.req_id,
            self.of_type,
            self.skipped,
        )


def encode_frame(type: int, req_id: int, payload: bytes, version: int = PROTOCOL_VERSION) -> bytes:
    """The frame carrying ``payload``; raises LocalProtocolError if it cannot be sent."""
    if len(payload) > MAX_PAYLOAD:
        raise LocalProtocolError("payload of %d bytes exceeds %d" % (len(payload), MAX_PAYLOAD))
    if not 0 <= req_id <= 0xFFFF or not 0 <= type <= 0xFF:
        raise LocalProtocolError("req_id or type out of range")
    body = struct.pack(">BBHH", version, type, req_id, len(payload)) + payload
    return MAGIC + body + struct.pack(">I", crc32(body))


def seal(head_and_payload: bytes) -> bytes:
    """Append the CRC to a frame built by hand (start marker through payload)."""
    return head_and_payload + struct.pack(">I", crc32(head_and_payload[2:]))


class Decoder:
    """Bytes in, ``RawFrame`` or ``BadFrame`` out; see the module docstring."""

    def __init__(self) -> None:
        self._buf = bytearray()
        self._pos = 0
        self._truncate = False
        self._garbage = 0  # bytes skipped in the current run outside frames
        self._quiet = False  # the current run follows a bad frame: part of its damage

    @property
    def pending(self) -> int:
        """Bytes received and not yet decoded."""
        return len(self._buf) - self._pos

    def feed(self, data: bytes) -> None:
        if self._pos:
            self._buf = self._buf[self._pos :]
            self._pos = 0
        if len(self._buf) + len(data) > BUFFER_CAP:
            raise LocalProtocolError("receive buffer full: drain events before feeding more")
        self._buf.extend(data)

    def truncate(self) -> None:
        """Give up on incomplete frames: every frame still incomplete in the buffer becomes
        ``E_TRUNCATED`` (the stream ended, or the caller stopped waiting for it)."""
        self._truncate = True

    def _skip_to_marker(self, start: int) -> None:
        """Move to the next start marker at or after ``start``, counting skipped bytes."""
        buf = self._buf
        i = buf.find(MAGIC, start)
        if i < 0:
            i = len(buf)
            if i > start and buf[i - 1] == MAGIC[0]:
                i -= 1  # may be the first byte of a marker still arriving
        self._garbage += i - self._pos
        self._pos = i

    def _flush_garbage(self) -> "BadFrame | None":
        count = self._garbage
        quiet = self._quiet
        self._garbage = 0
        self._quiet = False
        if count and not quiet:
            return BadFrame(E_GARBAGE, "", skipped=count)
        return None

    def _bad(self, start: int, code: int, detail: str = "") -> BadFrame:
        """Drop the frame starting at ``start``; what follows up to a marker is its damage."""
        self._pos = start + 1
        self._quiet = True
        return BadFrame(code, detail, skipped=1)

    def next(self) -> "RawFrame | BadFrame | None":
        """The next frame or error, or None when more bytes are needed."""
        while True:
            buf = self._buf
            start = self._pos
            n = len(buf)
            if start >= n:
                if self._truncate:
                    self._truncate = False
                    return self._flush_garbage()
                return None
            if buf[start] != MAGIC[0] or (n - start >= 2 and buf[start + 1] != MAGIC[1]):
                self._skip_to_marker(start + 1)
                if self._pos < n or self._garbage >= MAX_FRAME:
                    ev = self._flush_garbage()
                    if ev is not None:
                        return ev
                continue
            ev = self._flush_garbage()
            if ev is not None:
                return ev
            if n - start < HEADER_LEN:
                return self._incomplete(start)
            version, type_, req_id, length = struct.unpack_from(">BBHH", buf, start + 2)
            if length > MAX_PAYLOAD:
                return self._bad(start, E_TOO_LARGE, "length %d" % length)
            end = start + HEADER_LEN + length + CRC_LEN
            if n < end:
                return self._incomplete(start)
            (crc,) = struct.unpack_from(">I", buf, end - CRC_LEN)
            if crc32(bytes(buf[start + 2 : end - CRC_LEN])) != crc:
                return self._bad(start, E_BAD_CRC)
            self._pos = end
            return RawFrame(version, type_, req_id, bytes(buf[start:end]))

    def _incomplete(self, start: int) -> "BadFrame | None":
        if not self._truncate:
            return None
        # The rest of the buffer up to a marker is this frame's damage; what arrives later
        # is a fresh stream (the caller ended this one, or gave up waiting for it).
        self._pos = start + 1
        self._skip_to_marker(start + 1)
        self._garbage = 0
        self._quiet = False
        return BadFrame(E_TRUNCATED, "frame incomplete", skipped=1)


__all__ = ["BadFrame", "Decoder", "RawFrame", "RemoteProtocolError", "encode_frame", "seal"]
