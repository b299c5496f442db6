"""The link-fault seam: a TCP proxy between clients and a firmware server, applying link faults.

``LinkProxy(emu, target)`` listens where clients connect and forwards each connection to
``target`` (the firmware's own TCP or Modbus server). It follows the emulator's active link
faults (``emu.link_faults``, announced through ``emu.link_listeners``) and applies them to the
byte streams, both directions:

- ``link_disconnect``: every open connection is dropped at once, new ones are closed on
  arrival, until the fault is cleared;
- ``link_freeze seconds=S``: nothing is forwarded for S seconds (bytes wait, none are lost);
- ``link_delay ms=M``: every chunk is delivered M ms after it arrived (order kept);
- ``link_corrupt rate=R``: each byte is replaced by a random one with probability R.

The firmware never knows: its sockets see a client that is slow, silent, gone or noisy. The
printed board URL is the proxy's. With ``proxy_line`` the proxy tells the firmware who the
client is, as a load balancer does: each upstream connection starts with one line of HAProxy's
PROXY protocol, version 1 (``PROXY TCP4 CLIENT PROXY CPORT PPORT\r\n``; ``PROXY UNKNOWN`` for
a client that is not IPv4), which the firmware's Modbus server reads to apply its write
allow-list to the client's address rather than the proxy's.
"""

from __future__ import annotations

import asyncio
import contextlib
import ipaddress
import random
import time
from typing import Any

from emulator.sim import Emulator

CHUNK = 4096
QUEUE_CHUNKS = 16


def _ipv4(addr: object) -> tuple[str, int] | None:
    """(IPv4 address, port) of a socket address, also of an IPv4-mapped IPv6 one; else None."""
    if not isinstance(addr, tuple) or len(addr) < 2 or not isinstance(addr[0], str):
        return None
    try:
        return str(ipaddress.IPv4Address(addr[0].removeprefix("::ffff:"))), int(addr[1])
    except ValueError:
        return None


def proxy_line(peer: object, local: object) -> bytes:
    """The PROXY protocol v1 line for a connection from ``peer`` accepted at ``local``."""
    src, dst = _ipv4(peer), _ipv4(local)
    if src is None or dst is None:
        return b"PROXY UNKNOWN\r\n"
    return f"PROXY TCP4 {src[0]} {dst[0]} {src[1]} {dst[1]}\r\n".encode()


class LinkProxy:
    def __init__(self, emu: Emulator, target: tuple[str, int], seed: int = 0,
                 proxy_line: bool = False) -> None:
        self.emu = emu
        self.target = target
        self.proxy_line = proxy_line
        self.rng = random.Random(seed)
        self.faults: dict[str, dict[str, Any]] = dict(emu.link_faults)
        self.freeze_until = 0.0
        self.writers: set[asyncio.StreamWriter] = set()
        self.tasks: set[asyncio.Task[Any]] = set()
        self.server: asyncio.Server | None = None
        self.address: tuple[str, int] = ("", 0)
        emu.link_listeners.append(self._on_faults)

    async def start(self, host: str = "127.0.0.1", port: int = 0) -> tuple[str, int]:
        self.server = await asyncio.start_server(self._client, host, port)
        self.address = self.server.sockets[0].getsockname()[:2]
        return self.address

    def close(self) -> None:
        with contextlib.suppress(ValueError):
            self.emu.link_listeners.remove(self._on_faults)
        if self.server is not None:
            self.server.close()
        for w in list(self.writers):
            w.close()
        for t in list(self.tasks):
            t.cancel()

    def _on_faults(self, faults: dict[str, dict[str, Any]]) -> None:
        new = "link_freeze" in faults and faults["link_freeze"] != self.faults.get("link_freeze")
        self.faults = faults
        if new:
            self.freeze_until = time.monotonic() + float(faults["link_freeze"]["seconds"])
        elif "link_freeze" not in faults:
            self.freeze_until = 0.0
        if "link_disconnect" in faults:
            for w in list(self.writers):
                w.transport.abort()

    async def _client(self, reader: asyncio.StreamReader, writer: asyncio.StreamWriter) -> None:
        task = asyncio.current_task()
        if task is not None:
            self.tasks.add(task)
            task.add_done_callback(self.tasks.discard)
        try:
            await self._serve(reader, writer)
        except asyncio.CancelledError:
            # close() cancelled it: end quietly. Python 3.11's stream protocol asks a client
            # task that ended cancelled for its exception and logs the CancelledError.
            writer.transport.abort()

    async def _serve(self, reader: asyncio.StreamReader, writer: asyncio.StreamWriter) -> None:
        if "link_disconnect" in self.faults:
            writer.transport.abort()
            return
        try:
            up_r, up_w = await asyncio.open_connection(*self.target)
        except OSError:
            writer.close()
            return
        self.writers.update((writer, up_w))
        if self.proxy_line:
            up_w.write(proxy_line(writer.get_extra_info("peername"),
                                  writer.get_extra_info("sockname")))
        try:
            await asyncio.gather(self._pipe(reader, up_w), self._pipe(up_r, writer))
        finally:
            for w in (writer, up_w):
                self.writers.discard(w)
                w.close()

    async def _pipe(self, src: asyncio.StreamReader, dst: asyncio.StreamWriter) -> None:
        # bounded, so that a slow client slows the firmware's socket down as it would without
        # the proxy (the firmware then skips its measurements)
        queue: asyncio.Queue[tuple[float, bytes]] = asyncio.Queue(QUEUE_CHUNKS)
        sender = asyncio.create_task(self._send(queue, dst))
        try:
            while True:
                try:
                    data = await src.read(CHUNK)
                except OSError:
                    break
                if not data:
                    break
                await queue.put((time.monotonic(), self._corrupt(data)))
        finally:
            if sender.done():
                pass
            elif queue.full():
                sender.cancel()
            else:
                queue.put_nowait((0.0, b""))
            with contextlib.suppress(OSError, asyncio.CancelledError):
                await sender
            if dst.can_write_eof():
                with contextlib.suppress(OSError):
                    dst.write_eof()

    async def _send(self, queue: asyncio.Queue[tuple[float, bytes]],
                    dst: asyncio.StreamWriter) -> None:
        while True:
            t, data = await queue.get()
            if not data:
                return
            while True:
                now = time.monotonic()
                wait = self.freeze_until - now
                delay = self.faults.get("link_delay")
                if delay is not None:
                    wait = max(wait, t + float(delay["ms"]) / 1000 - now)
                if wait <= 0:
                    break
                await asyncio.sleep(min(wait, 0.05))
            dst.write(data)
            await dst.drain()

    def _corrupt(self, data: bytes) -> bytes:
        fault = self.faults.get("link_corrupt")
        if fault is None:
            return data
        rate = float(fault["rate"])
        out = bytearray(data)
        for i in range(len(out)):
            if self.rng.random() < rate:
                out[i] = self.rng.getrandbits(8)
        return bytes(out)
