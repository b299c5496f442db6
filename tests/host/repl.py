"""A MicroPython REPL on a pseudo-terminal, as a board on a USB serial port looks to mpremote.

The real ``micropython`` interpreter runs with its own pty as its terminal (it enables its raw
REPL, the one mpremote drives, only on a terminal), in a fresh directory that stands for the
board's flash file system. A thread copies bytes between that pty's master and a second pty
pair whose slave, ``device``, is what tools open: two programs on one slave would steal each
other's bytes.

The unix port cannot reset. With ``resettable=True`` the board can: its file system holds a
``machine.py`` (the unix port's ``machine`` is extensible) whose ``reset()`` ends the
interpreter, and the thread then starts it again as a board boots: running ``main.py``, then
the REPL (``micropython -i main.py``), on the same ``device``.
"""

from __future__ import annotations

import os
import select
import subprocess
import sys
import threading
import tty
from pathlib import Path

MICROPYTHON = str(Path(sys.executable).parent / "micropython")
RESET_CODE = 77
MACHINE_SHIM = (
    "# the test board's machine module: the unix port's, plus a reset that restarts it\n"
    "from umachine import *\n\n\n"
    "def reset():\n"
    f"    raise SystemExit({RESET_CODE})\n"
)


class PtyRepl:
    def __init__(self, root: Path, resettable: bool = False) -> None:
        self.root = root
        self.boots = 0
        self._stop = threading.Event()
        if resettable:
            (root / "machine.py").write_text(MACHINE_SHIM)
        self.dev_master, dev_slave = os.openpty()
        tty.setraw(dev_slave)
        self.device = os.ttyname(dev_slave)
        self._dev_slave = dev_slave  # kept open so the device does not hang up between tools
        self._start([MICROPYTHON])
        self._thread = threading.Thread(target=self._pump, daemon=True)
        self._thread.start()

    def _start(self, argv: list[str]) -> None:
        self.mp_master, mp_slave = os.openpty()
        tty.setraw(mp_slave)
        self.proc = subprocess.Popen(argv, stdin=mp_slave, stdout=mp_slave, stderr=mp_slave,
                                     cwd=self.root, close_fds=True, start_new_session=True)
        os.close(mp_slave)
        self.boots += 1

    def _pump(self) -> None:
        while not self._stop.is_set():
            if self.proc.poll() == RESET_CODE:  # reset: boot again, running main.py
                os.close(self.mp_master)
                boot = ["-i", "main.py"] if (self.root / "main.py").exists() else []
                self._start([MICROPYTHON, *boot])
            ends = {self.mp_master: self.dev_master, self.dev_master: self.mp_master}
            ready, _, _ = select.select(list(ends), [], [], 0.1)
            for fd in ready:
                try:
                    data = os.read(fd, 4096)
                except OSError:
                    continue
                if data:
                    os.write(ends[fd], data)

    def close(self) -> None:
        self._stop.set()
        self._thread.join(2)
        self.proc.kill()
        self.proc.wait(5)
        for fd in (self.mp_master, self.dev_master, self._dev_slave):
            os.close(fd)
