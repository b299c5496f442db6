"""``tcp://HOST:PORT``: the native protocol over TCP (the board's own network front end).

URL grammar: ``tcp://HOST:PORT`` (HOST a name, an IPv4 address or ``[IPv6]``); a bare
``HOST:PORT`` means the same. No query parameters. The board greets every new connection with
HELLO, and one connection is one session: when the board reboots the connection drops, and the
board client reconnects and sees the new boot id.
"""

from __future__ import annotations

import asyncio
import contextlib
import logging

from host.transports.stream import READ_SIZE, StreamTransport
from host.transports.url import BoardUrl

log = logging.getLogger(__name__)

SCHEME = "tcp"


class TcpTransport(StreamTransport):
    SCHEME = SCHEME

    def __init__(self, url: BoardUrl, key: bytes | None = None) -> None:
        super().__init__(url, key)
        url.check_params(())
        self.address = url.need_host_port("tcp://HOST:PORT, e.g. tcp://192.168.0.7:4840")
        self._reader: asyncio.StreamReader | None = None
        self._writer: asyncio.StreamWriter | None = None

    async def _connect(self) -> None:
        self._reader, self._writer = await asyncio.open_connection(*self.address)

    async def _read(self) -> bytes:
        if self._reader is None:
            raise ConnectionResetError("not connected")
        return await self._reader.read(READ_SIZE)

    async def _write(self, data: bytes) -> None:
        if self._writer is None:
            raise ConnectionResetError("not connected")
        self._writer.write(data)
        await self._writer.drain()

    async def _disconnect(self) -> None:
        writer, self._writer, self._reader = self._writer, None, None
        if writer is not None:
            writer.close()
            with contextlib.suppress(OSError, asyncio.CancelledError):
                await writer.wait_closed()


TRANSPORT = TcpTransport
