"""The board side of ``memory://``: the emulator on the test's event loop, one firmware
``Session`` per link (the same sans-I/O session the board's TCP and serial front ends run).

``MemoryBoard(emu, name)`` advances the emulator with the wall clock as a task, registers
``memory://name`` and serves each link: HELLO at once, replies to what arrives, pushes when
due. A reboot of the emulated board ends the link, as it ends a TCP connection on hardware.
``drop_links()`` ends every link without a reboot (a pulled cable); ``skip = N`` withholds the
next N measurements, as the firmware's front end does for a client that cannot keep up;
``caps`` are the capabilities its HELLO announces (without ``batch`` by default: a board
that sends one reading a frame, as boards before it did); ``freeze(s)`` holds every link for
``s`` seconds, both ways, new ones included (the emulator's
``link_freeze``: bytes wait, none are lost); ``mute = True`` keeps the sessions answering but
measuring nothing (a board whose network lives while its main loop does not).
"""

from __future__ import annotations

import asyncio
import contextlib
import json
from pathlib import Path
from typing import Any

from emulator import model
from emulator.control import run_wallclock
from emulator.sim import Emulator
from firmware.session import Session, board_key
from host.transports import memory
from protocol.constants import CAP_AUTH, CAP_CONFIG, CAP_EVENTS, CAP_SUBSCRIBE

TEDUSAR = Path(__file__).resolve().parents[2] / "models" / "tedusar"
KEY = bytes(range(32))
CAPS = CAP_AUTH | CAP_SUBSCRIBE | CAP_EVENTS | CAP_CONFIG


def tedusar(key: bytes | None = KEY) -> Emulator:
    cfg: dict[str, Any] = json.loads((TEDUSAR / "board.json").read_text())
    if key is not None:
        cfg["board"]["key"] = key.hex()
    return Emulator(model.load(TEDUSAR), board_config=cfg)


class MemoryBoard:
    def __init__(self, emu: Emulator, name: str = "board", caps: int = CAPS) -> None:
        self.emu = emu
        self.caps = caps  # the HELLO's capabilities (CAP_BATCH: SUBSCRIBE's per_frame used)
        self.name = name
        self.url = f"memory://{name}"
        self.links: list[memory.MemoryEnd] = []
        self.sessions = 0
        self.skip = 0  # measurements to withhold (a host that cannot keep up): a seq gap
        self.mute = False  # answer requests but send no measurement
        self.frozen_until = 0.0  # loop time until which every link is held
        self._tasks: set[asyncio.Task[None]] = set()
        self._stop = asyncio.Event()
        self._unlisten = lambda: None

    async def __aenter__(self) -> MemoryBoard:
        self._spawn(run_wallclock(self.emu, self._stop, tick_ms=5))
        self._unlisten = memory.listen(self.name, self._accept)
        return self

    async def __aexit__(self, *exc: object) -> None:
        self._unlisten()
        self._stop.set()
        self.drop_links()
        for task in list(self._tasks):
            task.cancel()
            with contextlib.suppress(asyncio.CancelledError):
                await task

    def _spawn(self, coro: Any) -> None:
        task = asyncio.get_running_loop().create_task(coro)
        self._tasks.add(task)
        task.add_done_callback(self._tasks.discard)

    def _accept(self, end: memory.MemoryEnd) -> None:
        self.links.append(end)
        self._spawn(self._serve(end))

    def freeze(self, seconds: float) -> None:
        """Hold every link, both ways, for ``seconds`` (nothing is lost, nothing moves)."""
        self.frozen_until = asyncio.get_running_loop().time() + seconds

    async def _thaw(self) -> None:
        loop = asyncio.get_running_loop()
        while loop.time() < self.frozen_until:
            await asyncio.sleep(self.frozen_until - loop.time())

    def drop_links(self) -> None:
        for end in self.links:
            end.close()
        self.links.clear()

    async def _serve(self, end: memory.MemoryEnd) -> None:
        emu = self.emu
        firmware = emu.firmware
        board = emu.board
        session = Session(board, board_key(board), emu.hal.random_bytes, "emulator", self.caps,
                          emu.hal.ticks_ms())
        self.sessions += 1
        await self._thaw()
        end.write(session.start(emu.hal.ticks_ms()))
        inbox: asyncio.Queue[bytes] = asyncio.Queue()

        async def pump() -> None:
            while True:
                data = await end.read()
                inbox.put_nowait(data)
                if not data:
                    return

        self._spawn(pump())
        while not end.closed:
            await self._thaw()
            if emu.firmware is not firmware:  # the board rebooted: the link goes down
                end.close()
                return
            now = emu.hal.ticks_ms()
            wait = max(0.0, min(session.next_due(now) - now, 20) / 1000)
            try:
                data = await asyncio.wait_for(inbox.get(), wait)
            except TimeoutError:
                data = None
            now = emu.hal.ticks_ms()
            out = b""
            if data is not None:
                if not data:
                    return
                out += session.receive(data, now)
            due = session.rate_hz and now >= session.meas_at
            send = not (due and (self.skip > 0 or self.mute))
            if not send and not self.mute:
                self.skip -= 1
            out += session.poll(now, send_measurement=send)
            if out and not end.closed:
                end.write(out)
