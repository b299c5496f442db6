"""The robot's emulated board as a child process, started as a user would (``--emulate``).

``EmulatedBoard.start(system_dir, control=...)`` runs ``dxboard emulate SYSTEM_DIR`` (this
interpreter, ``-m host.cli``) with the given key, or a fresh random one, in its environment,
reads the URLs it prints (``board:``, ``control:``, ``device: NAME URL`` lines) until the board
is up, and keeps the process (in a session of its own, so a terminal's Ctrl-C reaches the
daemon alone, and dying with the daemon, even a killed one); ``stop()`` sends SIGTERM and waits
(SIGKILL after a grace period). The host never imports the emulator: this is
the same process boundary a real board has.
"""

from __future__ import annotations

import asyncio
import contextlib
import logging
import os
import secrets
import signal
import sys
from dataclasses import dataclass, field
from pathlib import Path

from host.errors import UserError
from host.lifeline import lifeline

log = logging.getLogger(__name__)

START_TIMEOUT_S = 30.0
STOP_GRACE_S = 1.0  # SIGTERM, then SIGKILL: the emulator holds nothing worth waiting for


@dataclass
class EmulatedBoard:
    process: asyncio.subprocess.Process
    key: bytes
    board_url: str = ""
    control_url: str = ""
    urls: dict[str, str] = field(default_factory=dict)  # every "name: url" line
    devices: dict[str, str] = field(default_factory=dict)  # device name -> URL
    _drains: list[asyncio.Task[None]] = field(default_factory=list)

    @classmethod
    async def start(
        cls, system_dir: Path, control: str = "127.0.0.1:0", extra: tuple[str, ...] = (),
        key: bytes | None = None,
    ) -> EmulatedBoard:
        key = key or secrets.token_bytes(32)
        env = dict(os.environ, DXBOARD_KEY=key.hex())
        argv = [sys.executable, "-m", "host.cli", "emulate", str(system_dir),
                "--listen", "127.0.0.1:0", "--control", control, *extra]
        log.info("starting the emulated board: %s", " ".join(argv))
        # a session of its own: Ctrl-C on the terminal reaches the daemon alone, which stops
        # its nodes and then this board, in order (the board gone first read as a lost link
        # at every stop); it still dies with the daemon, even a killed one (host.lifeline)
        proc = await asyncio.create_subprocess_exec(
            *argv, env=env, stdout=asyncio.subprocess.PIPE, stderr=asyncio.subprocess.PIPE,
            preexec_fn=lifeline(), start_new_session=True,
        )
        board = cls(proc, key)
        try:
            await asyncio.wait_for(board._read_urls(), START_TIMEOUT_S)
        except (TimeoutError, EOFError):
            err = b""
            if proc.stderr is not None:
                with contextlib.suppress(TimeoutError):
                    err = await asyncio.wait_for(proc.stderr.read(4000), 2)
            await board.stop()
            last = err.decode(errors="replace").strip().splitlines()
            raise UserError(
                "the emulated board did not start" + (f": {last[-1]}" if last else ""),
                f"run 'dxboard emulate {system_dir}' to see why",
            ) from None
        # keep reading its output, so that a full pipe never stalls the board
        for stream in (proc.stdout, proc.stderr):
            if stream is not None:
                board._drains.append(asyncio.ensure_future(board._drain(stream)))
        return board

    @staticmethod
    async def _drain(stream: asyncio.StreamReader) -> None:
        while line := await stream.readline():
            log.debug("emulator: %s", line.decode(errors="replace").rstrip())

    def _take(self, line: bytes) -> None:
        name, _, rest = line.decode(errors="replace").strip().partition(": ")
        if name == "device":
            dev, _, url = rest.partition(" ")
            self.devices[dev] = url
        elif rest:
            self.urls[name] = rest
        self.board_url = self.urls.get("board", "")
        self.control_url = self.urls.get("control", "")

    async def _read_urls(self) -> None:
        assert self.process.stdout is not None
        while not (self.board_url and self.control_url):
            line = await self.process.stdout.readline()
            if not line:
                raise EOFError("the emulator exited")
            self._take(line)
        # the other lines (devices, modbus, ...) follow at once: take what comes promptly
        while True:
            try:
                line = await asyncio.wait_for(self.process.stdout.readline(), 0.2)
            except TimeoutError:
                break
            if not line:
                break
            self._take(line)

    async def stop(self, grace_s: float = STOP_GRACE_S) -> None:
        for task in self._drains:
            task.cancel()
        proc = self.process
        if proc.returncode is None:
            with contextlib.suppress(ProcessLookupError):
                proc.send_signal(signal.SIGTERM)
            try:
                await asyncio.wait_for(proc.wait(), grace_s)
            except TimeoutError:
                with contextlib.suppress(ProcessLookupError):
                    proc.kill()
                await proc.wait()
