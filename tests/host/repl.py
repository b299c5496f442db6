"""A MicroPython REPL on a pseudo-terminal, as a board on a USB serial port looks to mpremote.

The real ``micropython`` interpreter runs with its own pty as its terminal (it enables its raw
REPL, the one mpremote drives, only on a terminal), in a fresh directory that stands for the
board's flash file system. A thread copies bytes between that pty's master and a second pty
pair whose slave, ``device``, is what tools open: two programs on one slave would steal each
other's bytes.
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


class PtyRepl:
    def __init__(self, root: Path) -> None:
        self.root = root
        self._stop = threading.Event()
        self.mp_master, mp_slave = os.openpty()
        tty.setraw(mp_slave)
        self.dev_master, dev_slave = os.openpty()
        tty.setraw(dev_slave)
        self.device = os.ttyname(dev_slave)
        self._dev_slave = dev_slave  # kept open so the device does not hang up between tools
        self.proc = subprocess.Popen([MICROPYTHON], stdin=mp_slave, stdout=mp_slave,
                                     stderr=mp_slave, cwd=root, close_fds=True,
                                     start_new_session=True)
        os.close(mp_slave)
        self._thread = threading.Thread(target=self._pump, daemon=True)
        self._thread.start()

    def _pump(self) -> None:
        ends = {self.mp_master: self.dev_master, self.dev_master: self.mp_master}
        while not self._stop.is_set():
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
