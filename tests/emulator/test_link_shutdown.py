"""The link proxy stops quietly: a client connected when it closes leaves no asyncio error.

``benchmarks/board_firmware.py`` ended with ten "Exception in callback
StreamReaderProtocol.connection_made.<locals>.callback" tracebacks: each client task the proxy
cancelled on close was reported by Python 3.11's stream protocol, which asks a cancelled task
for its exception. The loop's exception handler must see nothing.
"""

from __future__ import annotations

import asyncio
from typing import Any

from emulator.link import LinkProxy
from tests.emulator.test_links import _emulator


async def _echo(reader: asyncio.StreamReader, writer: asyncio.StreamWriter) -> None:
    while data := await reader.read(4096):
        writer.write(data)
    writer.close()


async def _run() -> list[dict[str, Any]]:
    loop = asyncio.get_running_loop()
    errors: list[dict[str, Any]] = []
    loop.set_exception_handler(lambda _loop, ctx: errors.append(ctx))
    upstream = await asyncio.start_server(_echo, "127.0.0.1", 0)
    proxy = LinkProxy(_emulator(), upstream.sockets[0].getsockname()[:2])
    clients = []
    try:
        address = await proxy.start()
        for _ in range(3):
            r, w = await asyncio.open_connection(*address)
            w.write(b"ping")
            assert await asyncio.wait_for(r.readexactly(4), 30) == b"ping"
            clients.append(w)
    finally:
        proxy.close()
        for _ in range(50):  # let the cancelled client tasks finish and report
            await asyncio.sleep(0.01)
        for w in clients:
            w.close()
        upstream.close()
        await upstream.wait_closed()
    return errors


def test_closing_the_proxy_with_clients_connected_reports_no_error() -> None:
    errors = asyncio.run(_run())
    assert errors == [], [e.get("message") for e in errors]
