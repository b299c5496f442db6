"""The native protocol on any byte stream: the codec (``protocol.connection``) plus a backend.

Theory of operation. A ``StreamTransport`` owns a ``Connection(HOST, key)``. ``_open`` connects
the backend, then waits for the board's HELLO: a board that greets on connect (TCP) sends it at
once; if none arrives within ``HELLO_WAIT_S`` (a serial line to a board that booted long ago),
the host asks with HELLO_REQUEST and takes the HELLO that answers it (a greeting that comes
first, held up with the request by a frozen link, belongs to the session the answer replaces).
Messages before the first HELLO cannot be trusted to belong to this session and are dropped.
With a key, the host then proves it holds it (AUTH_PING) before anything else: the board counts
the session as the host's, keeps it open on its PINGs and never evicts it for a newcomer.
``_send`` signs through the codec (the key signs actuation, PROTOCOL.md §5); ``_receive`` feeds
bytes to the codec until it yields an event, and turns the end of the stream into ``LinkLost``.
A frame left incomplete when the stream ends becomes a ``BadFrame`` (E_TRUNCATED), never an
exception.

Backends implement ``_connect()``, ``_read() -> bytes`` (``b""`` at the end of the stream),
``_write(data)`` and ``_disconnect()``. Every native URL takes ``per_frame=K`` (1-10): the
readings a frame the board client asks of a board with capability ``batch`` (SUBSCRIBE's
``per_frame``, PROTOCOL.md §4.2); without it the client chooses (``host/board/client.py``).
"""

from __future__ import annotations

import asyncio
import collections
import logging
import random

from host.transports.base import (
    AUTH,
    BOOT_ID,
    CLAIM_REQ_ID,
    CONFIG,
    CYCLE,
    EVENTS,
    HELLO_REQ_ID,
    NAMES,
    PUSH,
    SAVE,
    Transport,
)
from host.transports.errors import LinkLost, VersionMismatch
from protocol.connection import HOST, Connection
from protocol.constants import E_AUTH_REQUIRED, E_BAD_TAG, E_VERSION, PROTOCOL_VERSION
from protocol.framing import BadFrame
from protocol.messages import AuthPing, Error, Hello, HelloRequest, Message, Pong

log = logging.getLogger(__name__)

HELLO_WAIT_S = 0.3
CLAIM_WAIT_S = 2.0
KEY_REFUSED = (E_BAD_TAG, E_AUTH_REQUIRED)  # the key is wrong, or the board has none
READ_SIZE = 4096
PER_FRAME = "per_frame"  # the URL parameter every native transport takes (1-10)


class StreamTransport(Transport):
    """The native protocol over a byte stream (see the module docstring)."""

    CAPS = frozenset({PUSH, EVENTS, AUTH, CYCLE, CONFIG, SAVE, NAMES, BOOT_ID})

    def __init__(self, url: object, key: bytes | None = None) -> None:
        super().__init__(url, key)  # type: ignore[arg-type]
        self.per_frame = self.url.int_param(PER_FRAME, 0, 1, 10)
        self.conn = Connection(HOST, key)
        self._events: collections.deque[Message | BadFrame] = collections.deque()
        self._eof = False

    async def _open(self) -> Hello:
        self.conn = Connection(HOST, self.key)
        self._events.clear()
        self._eof = False
        await self._connect()
        try:
            hello = await asyncio.wait_for(self._await_hello(None), HELLO_WAIT_S)
        except TimeoutError:
            req = HelloRequest(req_id=HELLO_REQ_ID)  # never an id the board client uses
            await self._write(self.conn.send(req))
            hello = await self._answer(req.req_id)
        if self.key is not None:
            await self._claim()
        return hello

    async def _claim(self) -> None:
        """Prove at once that this host holds the key (AUTH_PING, PROTOCOL.md §3), so that the
        board counts the session as the host's: never evicted for a newcomer. A board that
        refuses it (a wrong key, an older firmware) is left to refuse the commands later."""
        msg = AuthPing(random.getrandbits(32), req_id=CLAIM_REQ_ID)
        await self._write(self.conn.send(msg))
        others: list[Message | BadFrame] = []
        try:
            async with asyncio.timeout(CLAIM_WAIT_S):
                while True:
                    ev = await self._next_event()
                    if getattr(ev, "req_id", None) == CLAIM_REQ_ID:
                        if isinstance(ev, Pong):
                            self.key_check = "accepted"
                        elif isinstance(ev, Error) and ev.code in KEY_REFUSED:
                            self.key_check = f"refused: {ev.text or f'error {ev.code}'}"
                        else:  # an older firmware without AUTH_PING: commands will tell
                            log.info("%s: the board refused AUTH_PING: %r", self.url.text, ev)
                        break
                    others.append(ev)
        except TimeoutError:
            log.info("%s: no answer to AUTH_PING within %g s", self.url.text, CLAIM_WAIT_S)
        self._events.extendleft(reversed(others))

    async def _answer(self, req_id: int) -> Hello:
        """The HELLO that answers HELLO_REQUEST ``req_id``. A greeting (req_id 0) that comes
        first was sent before the board read the request (a link frozen for seconds holds
        both), and the answer starts a newer session: a claim signed for the greeting's nonce
        would be refused as a bad tag, a frozen link taken for a wrong key (issue 25, item 7).
        So the answer is awaited a while longer; a board that never sends one keeps the
        greeting's session."""
        hello = await self._await_hello(req_id)
        if hello.req_id == req_id:
            return hello
        try:
            return await asyncio.wait_for(self._await_hello(req_id, exact=True), CLAIM_WAIT_S)
        except TimeoutError:
            return hello

    async def _await_hello(self, req_id: int | None, exact: bool = False) -> Hello:
        while True:
            ev = await self._next_event()
            if isinstance(ev, Hello) and (req_id is None or ev.req_id == req_id
                                          or (ev.req_id == 0 and not exact)):
                return ev
            if isinstance(ev, BadFrame) and ev.code == E_VERSION:
                raise VersionMismatch(
                    f"{self.url.text}: the board speaks protocol version {ev.version}, this "
                    f"host version {PROTOCOL_VERSION}",
                    "flash matching firmware (dxboard flash) or use a matching dxboard")
            log.debug("%s: before HELLO, dropped %r", self.url.text, ev)

    async def _next_event(self) -> Message | BadFrame:
        while not self._events:
            if self._eof:
                raise self._closed_by_board()
            await self._fill()
        return self._events.popleft()

    def _closed_by_board(self) -> LinkLost:
        return LinkLost(f"{self.url.text}: the board closed the link",
                        "the board may have rebooted; reconnect")

    async def _fill(self) -> None:
        """Decode more events into ``_events``: one read from the backend (``_eof`` at the end
        of the stream). A backend that decodes as bytes arrive waits here instead."""
        data = await self._read()
        if not data:
            self._eof = True
        self.conn.receive_data(data)
        self._events.extend(self.conn.events())

    async def _send(self, msg: Message) -> None:
        await self._write(self.conn.send(msg))

    async def _receive(self) -> Message | BadFrame:
        return await self._next_event()

    async def _close(self) -> None:
        await self._disconnect()

    # --- backend ----------------------------------------------------------------------

    async def _connect(self) -> None:
        raise NotImplementedError

    async def _read(self) -> bytes:
        raise NotImplementedError

    async def _write(self, data: bytes) -> None:
        raise NotImplementedError

    async def _disconnect(self) -> None:
        raise NotImplementedError
