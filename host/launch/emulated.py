"""The robot's emulated board as a child process, started as a user would (``--emulate``).

``EmulatedBoard.start(system_dir, control=...)`` runs ``dxboard emulate SYSTEM_DIR`` (this
interpreter, ``-m host.cli``) with the given key, or a fresh random one, in its environment,
as a ``host.launch.procs.Child`` (in a session of its own, so a terminal's Ctrl-C reaches the
daemon alone, and dying with the daemon, even a killed one), and waits until it printed its
URLs (``board:``, ``control:``, ``device: NAME URL`` lines, printed as one block); ``stop()``
sends SIGTERM and waits (SIGKILL after a grace period). The host never imports the emulator:
this is the same process boundary a real board has.
"""

from __future__ import annotations

import logging
import os
import secrets
import signal
import sys
from dataclasses import dataclass
from pathlib import Path

from host.errors import UserError
from host.launch.procs import Child, Printed

log = logging.getLogger(__name__)

START_TIMEOUT_S = 30.0
STOP_GRACE_S = 1.0  # SIGTERM, then SIGKILL: the emulator holds nothing worth waiting for
SETTLE_S = 0.2  # the lines after board and control come in the same block: take them too


def _has_urls(child: Child) -> bool:
    urls = child.urls()
    return "board" in urls and "control" in urls


@dataclass
class EmulatedBoard(Printed):
    child: Child
    key: bytes

    @property
    def board_url(self) -> str:
        return self.urls.get("board", "")

    @property
    def control_url(self) -> str:
        return self.urls.get("control", "")

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
        board = cls(Child(argv, env=env, name="emulator", tie=signal.SIGKILL, any_thread=True),
                    key)
        try:
            up = await board.child.aready(_has_urls, START_TIMEOUT_S, SETTLE_S)
        except TimeoutError:
            up = False
        except BaseException:  # cancelled (Ctrl-C while it starts): its waiting thread ends
            board.child.stop(signal.SIGKILL, STOP_GRACE_S)
            raise
        if not up:
            await board.stop()
            last = list(board.child.err_tail)
            raise UserError(
                "the emulated board did not start" + (f": {last[-1]}" if last else ""),
                f"run 'dxboard emulate {system_dir}' to see why",
            ) from None
        return board

    async def stop(self, grace_s: float = STOP_GRACE_S) -> None:
        await self.child.astop(signal.SIGTERM, grace_s)
