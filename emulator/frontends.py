"""The firmware's own front ends on the emulated board (CPython runtime), and their seams.

``FrontEnds(emu)`` runs ``firmware.net.Net`` (native protocol over TCP and over a serial
stream) and ``firmware.modbus`` on the emulator's event loop, exactly as ``firmware/main.py``
does on the board, except that the emulator's clock drives the protection steps: after each
step (``emu.step_listeners``) the front ends ``pump`` their pushes, and after a reboot they
``attach`` to the new boot's firmware (which closes every client, as a reset does). Clients
never reach the firmware's servers directly: a ``LinkProxy`` (``emulator/link.py``) in front of
each applies the injected link faults, and its address is the one printed; the Modbus proxy
names each client to the firmware (a PROXY line), so the write allow-list sees the client.
The serial front end sits on the master side of a pseudo-terminal pair; clients open the
slave (``serial_path``). The CAN front end (``emulator/canbus.py``) puts ``firmware/can.py``
on a python-can bus; the original TEDUSAR format (``firmware/tug.py``) is served by the
firmware like Modbus.

``start(listen, modbus=None, serial=False, can=None, tug_at=None, tug_switch=False)`` must run
on the emulator's loop (see ``control.Background.run``); the ``urls`` it returns are the ones
``dxboard emulate`` prints.
"""

from __future__ import annotations

import asyncio
import contextlib
import os
import socket
import tty
from typing import Any

from emulator.link import LinkProxy
from emulator.sim import Emulator
from firmware import modbus, tug
from firmware.net import MAX_CLIENTS, READ_TIMEOUT_MS, Net
from firmware.session import FIRMWARE_VERSION
from protocol.constants import (
    CAP_AUTH,
    CAP_BATCH,
    CAP_CAN,
    CAP_CONFIG,
    CAP_EVENTS,
    CAP_MODBUS,
    CAP_SUBSCRIBE,
    CAP_VOLTAGE,
)

BASE_CAPS = CAP_AUTH | CAP_SUBSCRIBE | CAP_EVENTS | CAP_CONFIG | CAP_VOLTAGE | CAP_BATCH


def capabilities(modbus: bool, can: bool) -> int:
    return BASE_CAPS | (CAP_MODBUS if modbus else 0) | (CAP_CAN if can else 0)


def url_host(host: str) -> str:
    return f"[{host}]" if ":" in host else host


class FrontEnds:
    def __init__(self, emu: Emulator, seed: int = 0, read_timeout_ms: int = READ_TIMEOUT_MS,
                 max_clients: int = MAX_CLIENTS) -> None:
        self.emu = emu
        self.seed = seed
        self.read_timeout_ms = read_timeout_ms
        self.max_clients = max_clients
        self.net: Net | None = None
        self.proxies: list[LinkProxy] = []
        self.servers: list[Any] = []
        self.tasks: list[asyncio.Task[Any]] = []
        self.urls: dict[str, str] = {}
        self.serial_path = ""
        self._pty: tuple[int, int] | None = None
        self.can: Any = None

    async def start(self, listen: tuple[str, int] = ("127.0.0.1", 0),
                    modbus_at: tuple[str, int] | None = None, serial: bool = False,
                    can: str | None = None, tug_at: tuple[str, int] | None = None,
                    tug_switch: bool = False) -> dict[str, str]:
        emu = self.emu
        net = Net(emu.firmware, FIRMWARE_VERSION,
                  capabilities(modbus_at is not None, can is not None),
                  self.read_timeout_ms, self.max_clients)
        self.net = net
        emu.step_listeners.append(self._after_step)
        emu.reset_listeners.append(net.halt)
        self.tasks.append(asyncio.create_task(net.housekeeping()))
        server: Any = await net.serve_tcp("127.0.0.1", 0)
        self.servers.append(server)
        host, port = await self._proxy(server, listen)
        self.urls["board"] = f"tcp://{host}:{port}"
        if modbus_at is not None:
            mserver: Any = await modbus.serve(net, "127.0.0.1", 0, proxied=True)
            self.servers.append(mserver)
            host, port = await self.proxy_to(mserver.sockets[0].getsockname()[:2], modbus_at,
                                             proxy_line=True)
            self.urls["modbus"] = f"modbus+tcp://{host}:{port}"
        if tug_at is not None:
            tserver: Any = await tug.serve(net, "127.0.0.1", 0, tug_switch)
            self.servers.append(tserver)
            host, port = await self._proxy(tserver, tug_at)
            self.urls["tug"] = f"tug://{host}:{port}"
        if serial:
            await self.start_serial()
        if can is not None:
            self.start_can(can)
        return self.urls

    def start_can(self, spec: str, node_factory: Any = None) -> str:
        """The CAN front end on the bus ``spec``; ``node_factory(firmware)`` builds each
        boot's node (default: the firmware's ``CanNode`` in this interpreter)."""
        from emulator.canbus import CanFrontEnd, local_node

        front = CanFrontEnd(self.emu, spec, node_factory or local_node)
        self.can = front
        self.emu.step_listeners.append(self._pump_can)
        self.urls["can"] = front.url
        return front.url

    def _pump_can(self) -> None:
        if self.can is not None:
            self.can.pump(self.emu.hal.ticks_ms())

    async def _proxy(self, server: Any, listen: tuple[str, int]) -> tuple[str, int]:
        return await self.proxy_to(server.sockets[0].getsockname()[:2], listen)

    async def proxy_to(self, target: tuple[str, int], listen: tuple[str, int],
                       proxy_line: bool = False) -> tuple[str, int]:
        """A link-fault proxy listening on ``listen`` in front of ``target``: (host, port);
        ``proxy_line``: it names each client to the firmware first (the Modbus server)."""
        proxy = LinkProxy(self.emu, target, self.seed + len(self.proxies), proxy_line)
        self.proxies.append(proxy)
        host, port = await proxy.start(*listen)
        return url_host(host), port

    def _after_step(self) -> None:
        net = self.net
        if net is None:
            return
        if net.app is not self.emu.firmware:
            net.attach(self.emu.firmware)
        net.pump(self.emu.hal.ticks_ms())

    # --- serial -------------------------------------------------------------------------

    async def start_serial(self, relay_to: tuple[str, int] | socket.socket | None = None) -> str:
        """A pty pair; the firmware's serial front end on its master side: served here by
        ``Net.serve_serial``, or (``relay_to``, the micropython runtime) relayed byte for byte
        to the firmware's serial server there (or to a connected socket: the UART's wires of
        ``--board-rev``). The URL of the slave side."""
        master, slave = os.openpty()
        tty.setraw(slave)
        self._pty = (master, slave)
        self.serial_path = os.ttyname(slave)
        serve = self._serve_serial(master) if relay_to is None else \
            self._relay_serial(master, relay_to)
        self.tasks.append(asyncio.create_task(serve))
        self.urls["serial"] = "serial://" + self.serial_path
        return self.urls["serial"]

    async def _pty_streams(self, master: int) -> tuple[asyncio.StreamReader, _PipeWriter]:
        loop = asyncio.get_running_loop()
        reader = asyncio.StreamReader()
        rproto = asyncio.StreamReaderProtocol(reader)
        await loop.connect_read_pipe(lambda: rproto, os.fdopen(os.dup(master), "rb", 0))
        wtrans, _ = await loop.connect_write_pipe(
            asyncio.Protocol, os.fdopen(os.dup(master), "wb", 0))
        return reader, _PipeWriter(wtrans)

    async def _serve_serial(self, master: int) -> None:
        reader, writer = await self._pty_streams(master)
        assert self.net is not None
        await self.net.serve_serial(reader, writer)

    async def _relay_serial(self, master: int,
                            target: tuple[str, int] | socket.socket) -> None:
        reader, writer = await self._pty_streams(master)
        if isinstance(target, socket.socket):
            up_r, up_w = await asyncio.open_connection(sock=target)
        else:
            up_r, up_w = await asyncio.open_connection(*target)

        async def copy(src: asyncio.StreamReader, dst: Any) -> None:
            while data := await src.read(4096):
                dst.write(data)
                await dst.drain()

        try:
            await asyncio.gather(copy(reader, up_w), copy(up_r, writer))
        finally:
            up_w.close()

    async def stop(self) -> None:
        for listener in (self._after_step, self._pump_can):
            with contextlib.suppress(ValueError):
                self.emu.step_listeners.remove(listener)
        if self.net is not None:
            with contextlib.suppress(ValueError):
                self.emu.reset_listeners.remove(self.net.halt)
        for p in self.proxies:
            p.close()
        for s in self.servers:
            s.close()
        for t in self.tasks:
            t.cancel()
        for t in self.tasks:
            with contextlib.suppress(asyncio.CancelledError, OSError):
                await t
        if self.net is not None:
            for c in self.net.clients:
                c.close()
        if self.can is not None:
            self.can.close()
        if self._pty is not None:
            for fd in self._pty:
                with contextlib.suppress(OSError):
                    os.close(fd)


class _PipeWriter:
    """The little of ``StreamWriter`` that ``Net`` uses, over a write-pipe transport.

    A pty's master may not be read for a long time (no program on the slave); ``drain`` then
    waits until the transport's buffer is below 16 KiB, so the client's queue backs up and
    the session skips measurements, as it would for a slow TCP reader."""

    def __init__(self, transport: asyncio.WriteTransport) -> None:
        self.transport = transport

    def write(self, data: bytes) -> None:
        self.transport.write(data)

    async def drain(self) -> None:
        while self.transport.get_write_buffer_size() > 16384 and not self.transport.is_closing():
            await asyncio.sleep(0.01)

