"""One end of a dxboard session: frames and messages, roles, sessions and authentication.

Theory of operation. A ``Connection`` is either the BOARD or the HOST end. It wraps a
``framing.Decoder`` and turns good frames into ``Message`` objects and everything wrong into
``BadFrame`` events; it never raises on bytes from the wire. Its session state is a table
keyed by (state, event), as h11 does (PROTOCOL.md §3):

    IDLE    --HELLO-->  SESSION   the board sends HELLO / the host receives it
    SESSION --HELLO-->  SESSION   a new session: new nonce, the counter starts again

A HELLO carries the session nonce. The HOST signs every message whose class has
``AUTH = True`` (PROTOCOL.md §5): the payload gets a trailer of a 32-bit counter, strictly
increasing within the session, and a 16-byte tag, HMAC-SHA256(key, nonce || frame from the
start marker through the counter) cut to 16 bytes. The BOARD checks the tag in constant time
first, then the counter, and hands over the message only if both hold; otherwise it yields a
``BadFrame`` with E_BAD_TAG, E_REPLAYED, E_AUTH_REQUIRED or E_NO_SESSION. Reading needs no
key. The BOARD refuses a request with ``req_id`` 0 (E_MALFORMED, before any authentication):
0 marks pushes, so its reply could not be told from one. Sending a message the role may not
send, or an authenticated one without key or session, raises ``LocalProtocolError``.
"""

import struct

from protocol.auth import COUNTER_LEN, TAG_LEN, TRAILER_LEN, equal, frame_tag
from protocol.constants import (
    E_AUTH_REQUIRED,
    E_BAD_TAG,
    E_GARBAGE,
    E_MALFORMED,
    E_NO_SESSION,
    E_NOT_A_REQUEST,
    E_REPLAYED,
    E_UNKNOWN_TYPE,
    E_VERSION,
    PROTOCOL_VERSION,
)
from protocol.errors import LocalProtocolError
from protocol.framing import (
    CRC_LEN,
    HEADER_LEN,
    MAGIC,
    BadFrame,
    Decoder,
    RawFrame,
    encode_frame,
    seal,
)
from protocol.messages import BY_TYPE, Error, Hello, Message

BOARD = "board"
HOST = "host"
IDLE = "idle"
SESSION = "session"

# (state, event) -> next state; a pair missing here is a protocol error.
_TRANSITIONS = {
    (IDLE, "hello"): SESSION,
    (SESSION, "hello"): SESSION,
}

# errors that come with a trustworthy req_id, so the board answers them with ERROR
_REPLYABLE = (
    E_VERSION,
    E_UNKNOWN_TYPE,
    E_MALFORMED,
    E_NOT_A_REQUEST,
    E_AUTH_REQUIRED,
    E_BAD_TAG,
    E_REPLAYED,
    E_NO_SESSION,
)


class Connection:
    """The BOARD or HOST end of a session (see the module docstring)."""

    def __init__(self, role: str, key: "bytes | None" = None) -> None:
        if role not in (BOARD, HOST):
            raise LocalProtocolError("role must be 'board' or 'host'")
        self.role = role
        self.key = key
        self.state = IDLE
        self.nonce = b""
        self.counter = 0  # HOST: last counter sent; BOARD: last counter accepted
        self.peer_hello: "Hello | None" = None
        self._decoder = Decoder()
        self._next_req = 0
        self._sends = "B" if role == BOARD else "H"

    # --- session table ----------------------------------------------------------------

    def _transition(self, event: str) -> None:
        nxt = _TRANSITIONS.get((self.state, event))
        if nxt is None:
            raise LocalProtocolError("no transition from %s on %s" % (self.state, event))
        self.state = nxt

    def _start_session(self, nonce: bytes) -> None:
        self._transition("hello")
        self.nonce = bytes(nonce)
        self.counter = 0

    def next_request_id(self) -> int:
        """A fresh request id (1-65535, wrapping; 0 is kept for pushes)."""
        self._next_req = self._next_req % 0xFFFF + 1
        return self._next_req

    # --- sending ----------------------------------------------------------------------

    def send(self, msg: Message) -> bytes:
        """The bytes that carry ``msg`` (signed when the message needs it)."""
        if self._sends != msg.DIR:
            raise LocalProtocolError("%s cannot send %s" % (self.role, type(msg).__name__))
        try:
            payload = msg.payload()
        except ValueError as exc:
            raise LocalProtocolError(str(exc)) from None
        if isinstance(msg, Hello):
            self._start_session(msg.nonce)
        if not msg.AUTH:
            return encode_frame(msg.TYPE, msg.req_id, payload)
        if self.key is None:
            raise LocalProtocolError("%s needs a key" % type(msg).__name__)
        if self.state != SESSION:
            raise LocalProtocolError("%s needs a session: wait for HELLO" % type(msg).__name__)
        self.counter += 1
        head = MAGIC + struct.pack(
            ">BBHH", PROTOCOL_VERSION, msg.TYPE, msg.req_id, len(payload) + TRAILER_LEN
        )
        signed = head + payload + struct.pack(">I", self.counter)
        return seal(signed + frame_tag(self.key, self.nonce, signed))

    def error_reply(self, bad: BadFrame) -> "bytes | None":
        """BOARD: the ERROR frame answering ``bad``, or None when it gets no answer."""
        if bad.code not in _REPLYABLE:
            return None
        return self.send(Error(bad.code, bad.of_type, bad.text[:80], req_id=bad.req_id))

    # --- receiving --------------------------------------------------------------------

    def receive_data(self, data: bytes) -> None:
        """Feed bytes from the wire; ``b""`` means the stream ended."""
        if data:
            self._decoder.feed(data)
        else:
            self._decoder.truncate()

    def truncate(self) -> None:
        """Give up on a frame that stopped arriving (the caller's timeout expired)."""
        self._decoder.truncate()

    @property
    def pending(self) -> int:
        return self._decoder.pending

    def next_event(self) -> "Message | BadFrame | None":
        """The next message or error, or None when more bytes are needed."""
        frame = self._decoder.next()
        if frame is None or isinstance(frame, BadFrame):
            return frame
        return self._message(frame)

    def events(self) -> "list[Message | BadFrame]":
        """Every event decodable from the bytes fed so far."""
        out: "list[Message | BadFrame]" = []
        while True:
            ev = self.next_event()
            if ev is None:
                return out
            out.append(ev)

    def _message(self, frame: RawFrame) -> "Message | BadFrame":
        t = frame.type
        if frame.version != PROTOCOL_VERSION:
            return BadFrame(
                E_VERSION,
                "frame speaks version %d, this end version %d" % (frame.version, PROTOCOL_VERSION),
                frame.req_id,
                t,
                frame.version,
            )
        cls = BY_TYPE.get(t)
        if cls is None:
            return BadFrame(E_UNKNOWN_TYPE, "type 0x%02x" % t, frame.req_id, t)
        if self._sends == cls.DIR:
            return BadFrame(E_NOT_A_REQUEST, cls.__name__, frame.req_id, t)
        if self.role == BOARD and frame.req_id == 0:  # 0 marks pushes: a reply could not
            return BadFrame(E_MALFORMED, "req_id 0 is reserved for pushes", 0, t)  # tell
        payload = frame.payload
        if cls.AUTH and self.role == BOARD:
            checked = self._check_auth(frame, payload)
            if isinstance(checked, BadFrame):
                return checked
            payload = checked
        try:
            msg = cls.from_payload(payload, frame.req_id)
        except (ValueError, TypeError, KeyError) as exc:
            return BadFrame(E_MALFORMED, "%s: %s" % (cls.__name__, exc), frame.req_id, t)
        if isinstance(msg, Hello):
            self._start_session(msg.nonce)
            self.peer_hello = msg
        return msg

    def _check_auth(self, frame: RawFrame, payload: bytes) -> "bytes | BadFrame":
        t = frame.type
        if self.key is None:
            return BadFrame(E_AUTH_REQUIRED, "no key configured on the board", frame.req_id, t)
        if self.state != SESSION:
            return BadFrame(E_NO_SESSION, "", frame.req_id, t)
        if len(payload) < TRAILER_LEN:
            return BadFrame(E_AUTH_REQUIRED, "no counter and tag", frame.req_id, t)
        tag = payload[-TAG_LEN:]
        signed = frame.raw[: len(frame.raw) - CRC_LEN - TAG_LEN]
        if not equal(frame_tag(self.key, self.nonce, signed), tag):
            return BadFrame(E_BAD_TAG, "", frame.req_id, t)
        (counter,) = struct.unpack_from(">I", payload, len(payload) - TRAILER_LEN)
        if counter <= self.counter:
            detail = "counter %d <= %d" % (counter, self.counter)
            return BadFrame(E_REPLAYED, detail, frame.req_id, t)
        self.counter = counter
        return payload[: len(payload) - TRAILER_LEN]


__all__ = ["BOARD", "COUNTER_LEN", "E_GARBAGE", "HEADER_LEN", "HOST", "Connection"]
