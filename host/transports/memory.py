"""``memory://NAME``: the native protocol over an in-process byte pipe, the default test target.

URL grammar: ``memory://NAME[?per_frame=K]`` where NAME is what the board side registered with
``listen(NAME, accept)`` (STYLE.md 7, after pyserial's ``loop://`` and python-can's
``VirtualBus``). Opening the URL makes a ``pipe()`` (two ``MemoryEnd`` objects joined by
asyncio queues), hands one end to ``accept`` (the board side: a test or an emulator helper
that runs ``firmware.session.Session`` on it) and keeps the other. Either end's ``close()``
ends the stream for both, as a dropped TCP connection would. ``manipulate`` on the host end is
the fault seam (STYLE.md 8): a function applied to every chunk the host receives (corrupt,
truncate, drop). Everything runs on the caller's event loop; nothing here knows the board.
"""

from __future__ import annotations

import asyncio
import logging
from collections.abc import Callable

from host.transports.errors import BoardUnreachable
from host.transports.stream import PER_FRAME, StreamTransport
from host.transports.url import BoardUrl

log = logging.getLogger(__name__)

SCHEME = "memory"
_listeners: dict[str, Callable[[MemoryEnd], None]] = {}


class MemoryEnd:
    """One end of an in-memory byte pipe."""

    def __init__(self, inbox: asyncio.Queue[bytes], outbox: asyncio.Queue[bytes]) -> None:
        self._inbox = inbox
        self._outbox = outbox
        self.peer: MemoryEnd | None = None
        self.closed = False
        self.manipulate: Callable[[bytes], bytes] | None = None

    async def read(self) -> bytes:
        """The next chunk, or ``b""`` once either end closed."""
        if self.closed:
            return b""
        data = await self._inbox.get()
        if data and self.manipulate is not None:
            data = self.manipulate(data)
        return data

    def write(self, data: bytes) -> None:
        if self.closed:
            raise ConnectionResetError("memory pipe closed")
        if data:
            self._outbox.put_nowait(bytes(data))

    def close(self) -> None:
        if self.closed:
            return
        self.closed = True
        self._inbox.put_nowait(b"")
        if self.peer is not None and not self.peer.closed:
            self.peer.closed = True
            self._outbox.put_nowait(b"")


def pipe() -> tuple[MemoryEnd, MemoryEnd]:
    """Two connected ends: what one writes the other reads."""
    a2b: asyncio.Queue[bytes] = asyncio.Queue()
    b2a: asyncio.Queue[bytes] = asyncio.Queue()
    a, b = MemoryEnd(b2a, a2b), MemoryEnd(a2b, b2a)
    a.peer, b.peer = b, a
    return a, b


def listen(name: str, accept: Callable[[MemoryEnd], None]) -> Callable[[], None]:
    """Serve ``memory://name``: ``accept(end)`` gets the board end of every new link.
    Returns a function that stops listening."""
    _listeners[name] = accept

    def stop() -> None:
        if _listeners.get(name) is accept:
            del _listeners[name]

    return stop


class MemoryTransport(StreamTransport):
    SCHEME = SCHEME

    def __init__(self, url: BoardUrl, key: bytes | None = None) -> None:
        super().__init__(url, key)
        url.check_params((PER_FRAME,))
        self.name = url.host or url.path.strip("/")
        self.end: MemoryEnd | None = None

    async def _connect(self) -> None:
        accept = _listeners.get(self.name)
        if accept is None:
            raise BoardUnreachable(f"nothing listens on memory://{self.name}",
                                   "start the in-memory board first (memory.listen)")
        host_end, board_end = pipe()
        self.end = host_end
        accept(board_end)

    async def _read(self) -> bytes:
        if self.end is None:
            return b""
        return await self.end.read()

    async def _write(self, data: bytes) -> None:
        if self.end is None:
            raise ConnectionResetError("not connected")
        self.end.write(data)

    async def _disconnect(self) -> None:
        if self.end is not None:
            self.end.close()


TRANSPORT = MemoryTransport
