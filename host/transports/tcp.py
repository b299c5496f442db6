"""``tcp://HOST:PORT``: the native protocol over TCP (the board's own network front end).

URL grammar: ``tcp://HOST:PORT[?hold_ms=N][&per_frame=K]`` (HOST a name, an IPv4 address or
``[IPv6]``); a bare ``HOST:PORT`` means the same. ``per_frame`` (1-10): readings a frame asked
of a board that can batch them (``host/transports/stream.py``; default: the client's choice).
``hold_ms`` (0-100, default 0: off) trades latency for
CPU: after each arrival the socket is left unread for N ms, so that what the board sends
meanwhile arrives as one batch (at 100 Hz and 20 ms, two or three readings a wake-up instead
of one); every message, a reply or an event too, may reach the host up to N ms later. The
board greets every new connection with HELLO, and one connection is one session: when the board
reboots the connection drops, and the board client reconnects and sees the new boot id.

Theory of operation. The socket is an ``asyncio.Protocol`` (``_Link``), not a stream pair: a
board pushes a hundred measurements a second, and every one that passed through a
``StreamReader`` woke a reader task. Bytes are decoded where they arrive (``_received``, in the
loop's read callback), in slices no larger than a read of the stream transports (the codec's
buffer is capped). While the board client pumps (``pump``), each batch of decoded messages goes
straight to it; otherwise (opening, or a caller of ``receive``) they queue, and reading pauses
while more than ``QUEUE_HIGH`` wait, until the queue drains to half (back-pressure, as a
``StreamReader`` gives at its limit). The end of the connection cuts a frame left incomplete
(``BadFrame`` E_TRUNCATED, handed up first), then ends the pump and every read: ``LinkLost``,
"the board closed the link" on an orderly end, the socket's error otherwise. Writes wait while
the socket's send buffer is full (``pause_writing``) and fail once the connection is lost.
With ``hold_ms``, reading pauses after each batch handed to the pump and resumes by a timer;
the end of the connection is then seen when reading resumes.
"""

from __future__ import annotations

import asyncio
import contextlib
import logging
from collections.abc import Callable

from host.transports.stream import PER_FRAME, READ_SIZE, StreamTransport
from host.transports.url import BoardUrl
from protocol.framing import BadFrame
from protocol.messages import Message

log = logging.getLogger(__name__)

SCHEME = "tcp"
QUEUE_HIGH = 2048  # decoded messages waiting for a reader before reading pauses

Batch = list[Message | BadFrame]


class _Link(asyncio.Protocol):
    """asyncio's side of the socket: every callback goes to the transport that owns it."""

    def __init__(self, owner: TcpTransport) -> None:
        self.owner = owner

    def connection_made(self, transport: asyncio.BaseTransport) -> None:
        assert isinstance(transport, asyncio.Transport)
        self.owner._made(transport)

    def data_received(self, data: bytes) -> None:
        self.owner._received(data)

    def connection_lost(self, exc: Exception | None) -> None:
        self.owner._lost(exc)

    def pause_writing(self) -> None:
        self.owner._pause_writing()

    def resume_writing(self) -> None:
        self.owner._resume_writing()


class TcpTransport(StreamTransport):
    SCHEME = SCHEME

    def __init__(self, url: BoardUrl, key: bytes | None = None) -> None:
        super().__init__(url, key)
        url.check_params(("hold_ms", PER_FRAME))
        self.address = url.need_host_port("tcp://HOST:PORT, e.g. tcp://192.168.0.7:7000")
        self.hold_s = url.int_param("hold_ms", 0, 0, 100) / 1000
        self._held: asyncio.TimerHandle | None = None  # reading held until this fires
        self._sock: asyncio.Transport | None = None
        self._error: OSError | None = None  # why the connection ended, if not orderly
        self._paused = False  # reading paused: too many messages queued
        self._waiter: asyncio.Future[None] | None = None  # a reader waiting for messages
        self._deliver: Callable[[Batch], None] | None = None  # the pump's receiver
        self._pumping: asyncio.Future[None] | None = None  # ends (with an error) with the pump
        self._drained: asyncio.Future[None] | None = None  # writes wait on it while paused
        self._gone: asyncio.Future[None] | None = None  # done when the connection is lost

    # --- the socket's callbacks ---------------------------------------------------------

    def _made(self, sock: asyncio.Transport) -> None:
        self._sock = sock
        self._gone = asyncio.get_running_loop().create_future()

    def _received(self, data: bytes) -> None:
        conn = self.conn
        if len(data) <= READ_SIZE:
            conn.receive_data(data)
            batch = conn.events()
        else:
            batch = []
            for at in range(0, len(data), READ_SIZE):
                conn.receive_data(data[at:at + READ_SIZE])
                batch.extend(conn.events())
        if batch:
            self._hand_up(batch)

    def _hand_up(self, batch: Batch) -> None:
        deliver = self._deliver
        if deliver is not None and not self._events:
            if log.isEnabledFor(logging.DEBUG):
                for msg in batch:
                    log.debug("%s -> %r", self.url.text, msg)
            try:
                deliver(batch)
            except Exception as exc:  # the receiver's own failure ends its pump, not the loop
                self._end_pump(exc)
            if self.hold_s and self._held is None and self._sock is not None:
                self._sock.pause_reading()
                self._held = asyncio.get_running_loop().call_later(self.hold_s, self._release)
            return
        self._events.extend(batch)
        waiter = self._waiter
        if waiter is not None and not waiter.done():
            waiter.set_result(None)
        if len(self._events) > QUEUE_HIGH and not self._paused and self._sock is not None:
            self._paused = True
            self._sock.pause_reading()

    def _release(self) -> None:
        """The hold is over: read again (unless the queue holds reading back)."""
        self._held = None
        if self._sock is not None and not self._paused:
            self._sock.resume_reading()

    def _lost(self, exc: Exception | None) -> None:
        self._sock = None
        if self._held is not None:
            self._held.cancel()
            self._held = None
        self.conn.receive_data(b"")  # a frame cut off by the end of the connection
        tail = self.conn.events()
        if tail:
            self._hand_up(tail)
        if exc is None:
            self._eof = True
        else:
            self._error = exc if isinstance(exc, OSError) else ConnectionResetError(str(exc))
        self._end_pump(self._error or self._closed_by_board())
        for fut in (self._waiter, self._gone):
            if fut is not None and not fut.done():
                fut.set_result(None)
        drained = self._drained
        if drained is not None and not drained.done():
            drained.set_exception(ConnectionResetError("connection lost"))
            drained.exception()  # retrieved: no writer may be waiting on it

    def _end_pump(self, exc: BaseException) -> None:
        pumping = self._pumping
        if pumping is not None and not pumping.done():
            pumping.set_exception(exc)

    def _pause_writing(self) -> None:
        if self._drained is None or self._drained.done():
            self._drained = asyncio.get_running_loop().create_future()

    def _resume_writing(self) -> None:
        if self._drained is not None and not self._drained.done():
            self._drained.set_result(None)

    # --- the transport's half -------------------------------------------------------------

    async def _connect(self) -> None:
        self._error = None
        self._paused = False
        loop = asyncio.get_running_loop()
        await loop.create_connection(lambda: _Link(self), *self.address)

    async def _fill(self) -> None:
        if self._error is not None:
            raise self._error
        if self._sock is None:
            raise ConnectionResetError("not connected")
        waiter = self._waiter = asyncio.get_running_loop().create_future()
        try:
            await waiter
        finally:
            self._waiter = None

    async def _next_event(self) -> Message | BadFrame:
        msg = await super()._next_event()
        self._resume_reading()
        return msg

    def _resume_reading(self) -> None:
        if self._paused and len(self._events) <= QUEUE_HIGH // 2 and self._sock is not None:
            self._paused = False
            if self._held is None:
                self._sock.resume_reading()

    async def _pump(self, deliver: Callable[[Batch], None]) -> None:
        while self._events:  # what arrived before the pump started, first
            batch = list(self._events)
            self._events.clear()
            self._resume_reading()
            deliver(batch)
        if self._eof:
            raise self._closed_by_board()
        if self._error is not None:
            raise self._error
        if self._sock is None:
            raise ConnectionResetError("not connected")
        self._pumping = asyncio.get_running_loop().create_future()
        self._deliver = deliver
        try:
            await self._pumping  # ends only with the link (or the receiver's failure)
        finally:
            self._deliver = None
            self._pumping = None

    async def _write(self, data: bytes) -> None:
        sock = self._sock
        if sock is None:
            raise self._error or ConnectionResetError("not connected")
        sock.write(data)
        drained = self._drained
        if drained is not None and not drained.done():
            await drained

    async def _disconnect(self) -> None:
        sock, self._sock = self._sock, None
        if self._held is not None:
            self._held.cancel()
            self._held = None
        if sock is not None:
            sock.close()
        if self._gone is not None:
            with contextlib.suppress(asyncio.CancelledError):
                await self._gone


TRANSPORT = TcpTransport
