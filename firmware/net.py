"""The board's asyncio front ends: native protocol over TCP and over a serial byte stream.

Each connection (or the serial stream) gets a ``Session`` (``firmware/session.py``, sans I/O)
and two tasks: the reader feeds received bytes to the session and queues its replies; the
writer sends the client's queue. ``pump(now)``, called after every protection step, polls each
session and queues its pushes (events at once, measurements when due). Nothing here can hold
up protection: the protection step never waits for a client, each client's queue is bounded,
and a client whose queue holds more than ``SOFT_CAP`` bytes (a slow reader) has its due
measurements skipped (the session keeps counting, so the client sees the gap in ``seq``);
events are never skipped: a client that lets ``HARD_CAP`` bytes pile up is disconnected
instead. A flood of bytes is read ``READ_SIZE`` at a time with a yield after each chunk.
TCP sessions idle for ``read_timeout_ms`` (30 s; ``Session.idle_ms``: the host PINGs, a
stranger's PINGs do not count) are closed, which also ends half-open connections. At most
``max_clients`` (8) are served, of which ``reserved`` (2) only for authenticated sessions (the
host's, after its AUTH_PING): a newcomer when the board is full evicts the idlest
unauthenticated session, so idle strangers can never lock the host out, and the host's
session is never evicted (a newcomer is refused only when every slot is the host's).
``serve_serial`` serves a serial line: one session after another on the same stream, each
dropping an incomplete frame after ``FRAME_GAP_MS`` of silence.

``Net(app, firmware_version, capabilities)``; ``attach(app)`` after a reboot (closes every
client, as a reset would); ``await serve_tcp(host, port)`` returns the server;
``await serve_stream(reader, writer)`` serves a serial stream until it ends; ``pump(now)``;
``await protect()`` runs the protection loop (``App.step`` on the HAL clock, then ``pump``)
for the real board, where the emulator calls ``step`` and ``pump`` itself. ``housekeeping``
beats the supervisor's ``net`` task once a second. Runs on MicroPython's asyncio and CPython's.
"""

import asyncio

from firmware.session import FRAME_GAP_MS, Session, board_key
from protocol.compat import const

if False:  # typing only; MicroPython never imports typing (the block is compiled away)
    from typing import Any, Protocol

    from firmware.app import App
    from firmware.hal import Hal
    from firmware.tug import TugSession

    class ByteReader(Protocol):
        """The reading half of a byte stream (``asyncio.StreamReader``, a UART's stream)."""

        async def read(self, n: int) -> bytes: ...

    class ByteWriter(Protocol):
        """The writing half of a byte stream (``asyncio.StreamWriter``, a UART's stream, the
        emulator's pty writer)."""

        def write(self, data: bytes) -> None: ...

        async def drain(self) -> None: ...

    class ClosingWriter(ByteWriter, Protocol):
        """A byte stream's writing half that closes (``asyncio.StreamWriter``: TCP)."""

        def close(self) -> None: ...

        async def wait_closed(self) -> None: ...

READ_SIZE = const(512)
SOFT_CAP = const(2048)
HARD_CAP = const(32768)
MAX_CLIENTS = const(8)
RESERVED = const(2)  # of MAX_CLIENTS, only for authenticated (host) sessions
READ_TIMEOUT_MS = const(30000)
NET_SILENCE_MS = const(5000)

_sleep_ms = getattr(asyncio, "sleep_ms", None)


async def sleep_ms(ms: int) -> None:
    if _sleep_ms is not None:
        await _sleep_ms(ms)
    else:
        await asyncio.sleep(ms / 1000)


class Client:
    """One stream's session and its bounded output queue."""

    def __init__(self, session: "Session | TugSession", writer: "ByteWriter", name: str) -> None:
        self.session = session
        self.writer = writer
        self.name = name
        self.out: "list[bytes]" = []
        self.n = 0
        self.wake = asyncio.Event()
        self.closed = False
        self.skipped = 0  # measurements skipped for this client
        self.task: "asyncio.Task[Any] | None" = None  # the task reading this stream
        self.reading = False
        self.kicked = False
        self.limited = False  # counted against max_clients (a TCP connection)

    def queue(self, data: bytes) -> None:
        if not data or self.closed:
            return
        self.out.append(data)
        self.n += len(data)
        if self.n > HARD_CAP:
            self.close()
        self.wake.set()

    def close(self) -> None:
        """End this client (a reset, an overflow): its reader stops waiting at once."""
        self.closed = True
        self.out = []
        self.n = 0
        self.wake.set()
        if self.reading and self.task is not None and not self.kicked:
            self.kicked = True
            self.task.cancel()

    async def write_loop(self) -> None:
        w = self.writer
        try:
            while not self.closed:
                await self.wake.wait()
                self.wake.clear()
                while self.out and not self.closed:
                    data = b"".join(self.out)
                    self.out = []
                    w.write(data)
                    await w.drain()
                    self.n -= len(data)
                    if self.n < 0:
                        self.n = 0
        except (OSError, asyncio.CancelledError):
            pass
        self.closed = True


class Net:
    def __init__(self, app: "App", firmware_version: str, capabilities: int,
                 read_timeout_ms: int = READ_TIMEOUT_MS, max_clients: int = MAX_CLIENTS,
                 reserved: int = RESERVED) -> None:
        self.firmware_version = firmware_version
        self.capabilities = capabilities
        self.read_timeout_ms = read_timeout_ms
        self.max_clients = max_clients
        self.reserved = reserved
        self.clients: "list[Client]" = []
        # other streams (Modbus): (writer, its task, never None inside the stream's coroutine)
        self.links: "list[tuple[ClosingWriter, Any]]" = []
        self.halted = False
        self.app = app
        self.hal: "Hal" = app.hal
        self.task = -1
        self.attach(app)

    def attach(self, app: "App") -> None:
        """Serve ``app`` (a new boot): every client of the old one is closed."""
        self.app = app
        self.hal = app.hal
        self.halted = False
        self.close_all()
        sup = app.supervisor
        self.task = sup.register("net", NET_SILENCE_MS, self.hal.ticks_ms())

    def close_all(self) -> None:
        """Close every client and every other stream (as a reset of the board does)."""
        for c in self.clients:
            c.close()
        for w, task in self.links:
            try:  # noqa: SIM105 (MicroPython has no contextlib)
                w.close()
            except OSError:
                pass
            task.cancel()  # MicroPython does not wake a read pending on a closed socket

    def halt(self) -> None:
        """The board is held in reset: close everything, serve nothing until ``attach``."""
        self.halted = True
        self.close_all()

    def now(self) -> int:
        return self.hal.ticks_ms()

    def _session(self, frame_gap_ms: int = 0) -> Session:
        board = self.app.board
        return Session(board, board_key(board), self.hal.random_bytes, self.firmware_version,
                       self.capabilities, self.now(), frame_gap_ms)

    # --- pushes, after every protection step ------------------------------------------

    def pump(self, now: int) -> None:
        for c in self.clients:
            if c.closed:
                continue
            room = c.n < SOFT_CAP
            data = c.session.poll(now, room)
            if not room and c.session.rate_hz:
                c.skipped += 1
            c.queue(data)

    async def protect(self) -> None:
        """The protection loop of the real board: one step per tick, then the pushes."""
        app = self.app
        while True:
            due = app.step()
            now = self.now()
            self.pump(now)
            wait = due - now
            await sleep_ms(wait if wait > 0 else 0)

    async def housekeeping(self) -> None:
        while True:
            self.app.supervisor.beat(self.task, self.now())
            await sleep_ms(1000)

    # --- streams ----------------------------------------------------------------------

    async def serve_tcp(self, host: str = "0.0.0.0", port: int = 7000) -> "asyncio.Server":
        return await asyncio.start_server(self._tcp_client, host, port)

    async def _tcp_client(self, reader: "ByteReader", writer: "ClosingWriter") -> None:
        if self.halted or not self._make_room():
            await _close(writer)
            return
        await self.serve_stream(reader, writer, self.read_timeout_ms)

    def _make_room(self) -> bool:
        """Room for one more connection: evict the idlest unauthenticated session when the
        board is full or strangers hold every unreserved slot. False only when every slot is
        the authenticated host's (which a newcomer never displaces)."""
        live = [c for c in self.clients if not c.closed and c.limited]  # TCP, not serial
        # a limited client is a TCP one, whose session is a native Session, never a TugSession
        strangers = [c for c in live if not c.session.authenticated]  # type: ignore[union-attr]
        if len(live) < self.max_clients and len(strangers) < self.max_clients - self.reserved:
            return True
        if not strangers:
            return False
        now = self.now()
        victim = strangers[0]
        for c in strangers:
            if c.session.idle_ms(now) > victim.session.idle_ms(now):  # type: ignore[union-attr]
                victim = c
        victim.close()
        return True

    async def serve_serial(self, reader: "ByteReader", writer: "ByteWriter") -> None:
        """Serve a serial line until its stream ends (a UART's never does)."""
        while True:
            if self.halted:  # bytes sent to a board held in reset are lost
                if not await reader.read(READ_SIZE):
                    return
                continue
            if await self.serve_stream(reader, writer, close=False, frame_gap_ms=FRAME_GAP_MS):
                return
            await sleep_ms(10)  # the board closed the session (a reset): serve a new one

    async def serve_stream(self, reader: "ByteReader", writer: "ByteWriter", timeout_ms: int = 0,
                           name: str = "", close: bool = True,
                           session: "Session | TugSession | None" = None,
                           frame_gap_ms: int = 0) -> bool:
        """Serve one byte stream until it ends (``timeout_ms`` 0: never time out); a serial
        port passes ``close=False`` so that the next session can use it, and
        ``frame_gap_ms=FRAME_GAP_MS``: an incomplete frame followed by that much silence is
        dropped (PROTOCOL.md §2), so a host that opens the port after another program left
        half a frame behind is heard at once. ``session``: another front end's sans-I/O session
        with the same methods (``firmware/tug.py``). True when the stream itself ended."""
        ended = False
        s = session if session is not None else self._session(frame_gap_ms)
        c = Client(s, writer, name)
        c.limited = timeout_ms > 0
        self.clients.append(c)
        c.queue(s.start(self.now()))
        wt = asyncio.create_task(c.write_loop())
        c.task = asyncio.current_task()
        try:
            while not c.closed:
                c.reading = True
                try:
                    if timeout_ms:
                        # (a stream with a timeout is a native Session's: TCP)
                        left = timeout_ms - s.idle_ms(self.now())  # type: ignore[union-attr]
                        if left <= 0:  # idle for too long (see Session.idle_ms)
                            break
                        data = await asyncio.wait_for(reader.read(READ_SIZE),
                                                      left / 1000)
                    else:
                        data = await reader.read(READ_SIZE)
                except asyncio.TimeoutError:  # noqa: UP041 (MicroPython has no builtin TimeoutError)
                    continue  # the loop checks how idle the session is now
                except asyncio.CancelledError:
                    if c.kicked:  # closed by the board itself: not a cancellation of ours
                        break
                    raise
                finally:
                    c.reading = False
                if c.closed:
                    break
                if not data:
                    s.receive(b"", self.now())
                    ended = True
                    break
                c.queue(s.receive(data, self.now()))
                c.queue(s.poll(self.now(), c.n < SOFT_CAP))  # a Reboot's ACK, new events
                await asyncio.sleep(0)  # a flood must not starve the others
        except OSError:
            ended = True
        finally:
            c.close()
            if c in self.clients:
                self.clients.remove(c)
            wt.cancel()
            if close:  # a TCP stream (a serial one is served with close=False)
                await _close(writer)  # type: ignore[arg-type]
        return ended


async def _close(writer: "ClosingWriter") -> None:
    try:
        writer.close()
        await writer.wait_closed()
    except (OSError, asyncio.CancelledError):
        pass
