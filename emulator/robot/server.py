"""The virtual robot's devices as TCP servers, powered by the emulated board's electronics.

``Robot(emu, specs)`` serves every device of ``robot.yaml`` on its own TCP port (port 0: a free
one, kept for the whole run so the printed URL stays valid across power cycles). It runs on the
emulator's event loop (``Background.run(robot.start())``), so it reads the electronics from the
thread that advances them and never from another.

A device on a board channel follows the channel's ``Load`` (``emulator.electronics``), whose
faults it never re-implements::

    state     when (read from the load)                    the device's socket
    off       not powered, or open_load / short            closed: connections refused,
                                                             open ones dropped
    booting   powered, less than boot_ms since power-on    accepts, sends nothing
    hung      powered, booted, ``hang`` injected           connections stay open, no data
    ready     ``Load.ready(now)``                          a frame every 1/rate_hz s

A device runs on its own clock, not on the host's: when this loop was late (a busy machine),
the frames it missed go out together as soon as it runs again, each stamped (``t_ms``) with
the time it was due, as a real device's buffered frames would arrive (up to
``MAX_CATCH_UP_MS``; a longer stall loses the older ones).

A power cycle (a new ``on_since``, even one shorter than a poll) drops every connection and
restarts the device's counters, as a real device's reboot does. A ``hang`` keeps drawing its
current (the load's ``idle_ma``) and a non-permanent one is cured by power-cycling: both are
the load's. A ``dropout`` changes only the measured current, not ``Load.ready``, so the data
continues through it. Devices without a channel are always ready.
"""

from __future__ import annotations

import asyncio
import contextlib
import logging
import random
import socket
from typing import TYPE_CHECKING, Any

from emulator.jsonlines import MAX_LINE, Lines, encode
from emulator.robot import devices as D
from emulator.robot.config import DeviceSpec
from emulator.sim import Emulator

if TYPE_CHECKING:
    from emulator.robot.world.arena import Arena
    from emulator.robot.world.server import WorldServer

log = logging.getLogger(__name__)

MAX_BACKLOG = 1 << 20  # bytes queued to a client that does not read: it is dropped
POLL_S = 0.005
MAX_CATCH_UP_MS = 2000  # frames due longer ago than this, when the loop stalled, are lost
OFF, BOOTING, HUNG, READY = "off", "booting", "hung", "ready"


def device_state(emu: Emulator, channel: int | None) -> tuple[str, int]:
    """The device's state and the time it was last powered on (ms), from the electronics."""
    if channel is None:
        return READY, 0
    load = emu.electronics.loads[channel]
    if not load.powered or "open_load" in load.faults or "short" in load.faults:
        return OFF, load.on_since
    if load.ready(emu.now):
        return READY, load.on_since
    return (HUNG if load.hung else BOOTING), load.on_since


def _exclusive(sock: Any, on: bool) -> None:
    """Make a bound, not listening socket the port's only holder, or undo it before listening.

    Bound with SO_REUSEADDR (as servers bind, past the TIME_WAITs of earlier connections), a
    socket that does not listen lets another SO_REUSEADDR socket bind the port and listen on
    it (zenoh's, asyncio's): the device could then never listen again, and its clients would
    reach that server. Linux refuses such a bind while the holder has the option cleared."""
    sock.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 0 if on else 1)


class DeviceServer:
    def __init__(self, device: D.SimDevice, emu: Emulator, host: str) -> None:
        self.device = device
        self.emu = emu
        self.host = host
        self.port = 0
        self.server: asyncio.Server | None = None
        self._held: socket.socket | None = None  # the port, bound while off
        self.clients: set[asyncio.StreamWriter] = set()
        self.state = OFF
        self.on_since = -1
        self.next_due = 0.0  # the next frame's time on the emulator's clock (ms)
        # commands: any JSON object, answered only when refused; booting or hung, nobody listens
        self._lines = Lines(fallback=self._command, error=lambda words: {"error": words},
                            listening=lambda: self.state == READY,
                            on_close=self.clients.discard)

    @property
    def name(self) -> str:
        return self.device.spec.name

    @property
    def url(self) -> str:
        return f"tcp://{self.host}:{self.port}"

    async def bind(self) -> None:
        """Take a port (not yet listening: connections are refused until ``open``)."""
        held, self._held = self._held, None
        if held is not None:  # the port kept while off
            self.server = await asyncio.start_server(self._client, sock=held, limit=MAX_LINE,
                                                     start_serving=False)
        else:
            self.server = await asyncio.start_server(self._client, self.host, self.port,
                                                     limit=MAX_LINE, start_serving=False)
        self.port = self.server.sockets[0].getsockname()[1]
        for sock in self.server.sockets:
            _exclusive(sock, True)

    async def open(self) -> None:
        if self.server is None:
            await self.bind()
        assert self.server is not None
        for sock in self.server.sockets:
            _exclusive(sock, False)  # as any server listens (past the port's TIME_WAITs)
        await self.server.start_serving()

    def close(self, keep_port: bool = True) -> None:
        """Stop serving (powered off). The port stays bound, not listening: connections are
        refused, and no other program is given the port meanwhile (its ``bind(0)``,
        ``connect()``, or a listener's bind with SO_REUSEADDR: ``_exclusive``), so the device
        comes back on its printed URL."""
        if self.server is not None:
            family = self.server.sockets[0].family
            self.server.close()
            self.server = None
            if keep_port:
                self._held = self._hold(family)
        if not keep_port and self._held is not None:
            self._held.close()
            self._held = None
        for w in list(self.clients):
            w.transport.abort()
        self.clients.clear()

    def _hold(self, family: int) -> socket.socket | None:
        held = socket.socket(family, socket.SOCK_STREAM)
        held.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
        try:
            held.bind((self.host, self.port))
        except OSError as exc:  # taken in between: open() binds afresh (and retries)
            log.warning("%s: cannot keep port %d while off: %s", self.name, self.port, exc)
            held.close()
            return None
        _exclusive(held, True)
        return held

    async def update(self) -> None:
        """Follow the electronics; send a frame if one is due."""
        state, on_since = device_state(self.emu, self.device.spec.channel)
        now = self.emu.now
        was_on = self.state != OFF
        if was_on and (state == OFF or on_since != self.on_since):
            log.info("%s: power off", self.name)
            self.close()
            was_on = False
        if state != OFF and not was_on:
            log.info("%s: power on", self.name)
            try:
                await self.open()
            except OSError as exc:  # the port was taken while the device was off: retry
                log.warning("%s: cannot listen on port %d again: %s", self.name, self.port, exc)
                self.state = OFF
                return
            self.device.reset(now)
        if (state == READY) != (self.state == READY):
            log.info("%s: %s", self.name, "working" if state == READY else state)
            self.device.working(state == READY, now)
            self.next_due = float(now)
        self.state, self.on_since = state, on_since
        if state != READY:
            return
        # a device keeps its own clock, whatever the host's load: frames come due on the
        # emulator's clock, and those the loop was late for go out together, each stamped with
        # the time it was due
        period = 1000.0 / self.device.spec.rate_hz
        if now - self.next_due > MAX_CATCH_UP_MS:  # stalled for long: those frames are lost
            self.next_due = now - MAX_CATCH_UP_MS
        while self.next_due <= now:
            t_ms = int(self.next_due)
            self.next_due += period
            self._send(self.device.frame(t_ms))

    def _send(self, frame: dict[str, Any]) -> None:
        line = encode(frame)
        for w in list(self.clients):
            if w.transport.get_write_buffer_size() > MAX_BACKLOG:
                log.warning("%s: a client does not read; dropping it", self.name)
                w.transport.abort()
                self.clients.discard(w)
            else:
                w.write(line)

    async def _client(self, reader: asyncio.StreamReader,
                      writer: asyncio.StreamWriter) -> None:
        self.clients.add(writer)
        await self._lines.serve(reader, writer)  # ends by dropping it from clients

    def _command(self, msg: dict[str, Any], conn: object) -> None:
        self.device.command(msg, self.emu.now)  # a ValueError is answered with its words


class Robot:
    """Every device of the robot, served while the emulator runs; with an ``arena``, also the
    world's skill servers (``emulator.robot.world``), bound by one truth to these devices."""

    def __init__(self, emu: Emulator, specs: list[DeviceSpec], host: str = "127.0.0.1",
                 arena: Arena | None = None) -> None:
        self.emu = emu
        self.world = D.RobotWorld()
        seed = emu.model.board.seed
        self.servers = [DeviceServer(D.make(s, self.world, random.Random(f"{seed}:{s.name}")),
                                     emu, host) for s in specs]
        self.arena = arena
        self.world_server: WorldServer | None = None
        self._task: asyncio.Task[None] | None = None

    async def start(self) -> dict[str, str]:
        """Bind every device's port; returns device name -> ``tcp://`` URL."""
        for s in self.servers:
            await s.bind()
        self.world.t_ms = self.emu.now
        for s in self.servers:
            await s.update()
        self._task = asyncio.get_running_loop().create_task(self._run())
        if self.arena is not None:
            from emulator.robot.world.server import WorldServer
            from emulator.robot.world.truth import BoardTruth

            truth = BoardTruth({s.name: s for s in self.servers}, lambda: self.emu.now)
            self.world_server = WorldServer(self.arena, truth, lambda: self.emu.now)
            await self.world_server.start()
        return {s.name: s.url for s in self.servers}

    @property
    def world_url(self) -> str | None:
        return None if self.world_server is None else self.world_server.url

    async def _run(self) -> None:
        while True:
            for s in self.servers:
                await s.update()
            await asyncio.sleep(POLL_S)  # frames come due on the emulator's clock

    async def stop(self) -> None:
        if self.world_server is not None:
            await self.world_server.stop()
            self.world_server = None
        if self._task is not None:
            self._task.cancel()
            with contextlib.suppress(asyncio.CancelledError):
                await self._task
            self._task = None
        for s in self.servers:
            s.close(keep_port=False)
