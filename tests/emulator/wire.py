"""Test helpers: ``dxboard emulate`` as a subprocess, and a minimal native-protocol client.

``Emulate(*options)`` starts ``dxboard emulate models/tedusar`` with a key in the environment
(the launcher's ``host.launch.boards.RunningBoard``) and parses the URLs it prints; ``Wire`` is
a raw asyncio client on ``protocol.connection`` (the host's own BoardClient is tested elsewhere;
these tests look at the board's bytes). ``board_bench(rev, flash)`` is an in-process emulator of
a board revision on its part models (the shipped firmware in one ``micropython`` process) with
the tedusar devices on, and ``devices_on`` puts them back on between tests.
"""

from __future__ import annotations

import asyncio
import contextlib
import json
import sys
from collections.abc import Iterator
from pathlib import Path
from typing import Any

from emulator import model
from emulator.board_rt import BoardRuntime
from emulator.sim import Emulator
from firmware.hal.storage import FileStorage
from host.launch.boards import RunningBoard
from protocol.connection import HOST, Connection
from protocol.framing import BadFrame
from protocol.messages import Hello, Message

#: the most fed to a ``Connection`` at once, as the host's transports do: a read after the
#: client was descheduled may hold more than a ``Decoder`` takes undrained (``BUFFER_CAP``)
READ_SIZE = 4096

ROOT = Path(__file__).resolve().parents[2]
TEDUSAR = ROOT / "models" / "tedusar"
KEY = bytes(range(32))
DXBOARD = str(Path(sys.executable).parent / "dxboard")


#: how a conformance test names the firmware it runs against -> the options that start it:
#: the firmware's App in this interpreter or in micropython (on a remote HAL), or the shipped
#: boot.py and main.py of each board revision on its part models (``--board-rev``: rev A's
#: INA226, rev B's INA3221, rev C's PROFET smart switches)
RUNTIMES: dict[str, tuple[str, ...]] = {
    "cpython": ("--runtime", "cpython"),
    "micropython": ("--runtime", "micropython"),
    "rev-a": ("--runtime", "micropython", "--board-rev", "rev-a"),
    "rev-b": ("--runtime", "micropython", "--board-rev", "rev-b"),
    "rev-c": ("--runtime", "micropython", "--board-rev", "rev-c"),
}


#: the tedusar channels with a device the board benches switch on (2, the computer, is on)
DEVICES = (0, 1, 3, 4, 5, 6, 7)


@contextlib.contextmanager
def board_bench(rev: str, flash: Path) -> Iterator[tuple[Emulator, BoardRuntime]]:
    """Revision ``rev`` booted on its part models, every device on; stopped on leaving."""
    rt = BoardRuntime(rev, flash)
    try:
        cfg = json.loads((TEDUSAR / "board.json").read_text())
        emu = Emulator(model.load(TEDUSAR), storage=FileStorage(str(flash)), board_config=cfg,
                       firmware_factory=rt.factory)
        emu.parts = rt
        emu.advance(500)
        for ch in DEVICES:
            assert emu.board.switch(ch, True)[0] == 0
        emu.advance(2000)
        yield emu, rt
    finally:
        rt.close()


def devices_on(e: Emulator) -> None:
    """Every device on again (a test may have left one off or tripped)."""
    for ch in DEVICES:
        if not e.board.channel_status(ch)[0]:
            e.board.clear(ch)
            e.board.switch(ch, True)
    e.advance(1500)


class Emulate(RunningBoard):
    """``dxboard emulate models/tedusar OPTIONS`` (the launcher's ``RunningBoard``) with
    ``key`` (None: no key at all) in its environment; a context manager."""

    def __init__(self, *options: str, key: bytes | None = KEY) -> None:
        super().__init__(TEDUSAR, *options, key=key, robot=False)

    def address(self, name: str = "board") -> tuple[str, int]:
        rest = self.urls[name].split("://", 1)[1]
        host, _, port = rest.rpartition(":")
        return host, int(port)


class Wire:
    """A host end over TCP: ``send`` requests, ``expect`` replies, collect pushes."""

    def __init__(self, reader: asyncio.StreamReader, writer: asyncio.StreamWriter,
                 key: bytes | None = KEY) -> None:
        self.reader = reader
        self.writer = writer
        self.conn = Connection(HOST, key)
        self.hello: Hello | None = None
        self.backlog: list[Message | BadFrame] = []

    @classmethod
    async def open(cls, address: tuple[str, int], key: bytes | None = KEY) -> Wire:
        r, w = await asyncio.open_connection(*address)
        wire = cls(r, w, key)
        got = await wire.next(lambda m: isinstance(m, Hello))
        assert isinstance(got, Hello)
        wire.hello = got
        return wire

    async def next(self, pred: Any, timeout: float = 30.0) -> Message | BadFrame:
        """The next event matching ``pred``; others stay in ``backlog``."""
        loop = asyncio.get_running_loop()
        end = loop.time() + timeout
        while True:
            for i, ev in enumerate(self.backlog):
                if pred(ev):
                    return self.backlog.pop(i)
            left = end - loop.time()
            if left <= 0:
                raise AssertionError(f"nothing matching within {timeout} s: {self.backlog!r}")
            try:
                data = await asyncio.wait_for(self.reader.read(READ_SIZE), left)
            except TimeoutError:
                continue  # the deadline: said above, with what arrived
            if not data:
                raise AssertionError("connection closed")
            self.conn.receive_data(data)
            self.backlog.extend(self.conn.events())

    async def request(self, msg: Message, timeout: float = 30.0) -> Message | BadFrame:
        msg.req_id = self.conn.next_request_id()
        self.writer.write(self.conn.send(msg))
        await self.writer.drain()
        rid = msg.req_id
        return await self.next(lambda m: getattr(m, "req_id", None) == rid, timeout)

    async def close(self) -> None:
        self.writer.close()
        with contextlib.suppress(OSError):
            await self.writer.wait_closed()
