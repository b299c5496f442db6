"""Machine-wide slots for test modules, so that suites side by side queue instead of starving.

Under ``make test`` each test module holds one of ``count()`` slots shared by every pytest
process on the machine while it runs: its first test takes a slot, the end of the module gives
it back. One suite has at most ``count()`` workers (``make test``: 4), so alone it never
waits; two suites side by side (8 workers on 2 cores) ran eight modules at once, up to eight
whole robots (a load of 67; topics silent for 90 s, 11 failures), and with slots for the
process-starting modules only, four robots beside four CPU-bound modules (a load of 37, 3
failures). Now the machine runs at most ``count()`` modules of all its suites at once, as
one suite does. Slots are ``flock`` locks on files in one directory of the machine's
temporary directory: the kernel frees a dead process's slot. The wait does not count against
the test's own time limit (pytest-timeout's ``SIGALRM`` timer is paused).
"""

from __future__ import annotations

import contextlib
import fcntl
import os
import signal
import tempfile
import time
from collections.abc import Iterator
from pathlib import Path

POLL_S = 0.2
NONE = -1  # "held" where slots cannot be used: the suite goes on without them
DIR = Path(tempfile.gettempdir()) / "dxboard-test-slots"


def count() -> int:
    """Slots on this machine: the suite's own workers (4), more on a bigger machine."""
    return max(4, 2 * (os.cpu_count() or 1))


class Slots:
    """One process's hold on at most one slot of ``directory``."""

    def __init__(self, directory: Path = DIR, n: int | None = None) -> None:
        self.directory = directory
        self.n = count() if n is None else n
        self._held: int | None = None  # the open slot file's descriptor
        self.waited_s = 0.0  # all the time this process waited for a slot

    @property
    def held(self) -> bool:
        return self._held is not None

    def try_acquire(self) -> bool:
        """Take a free slot if there is one (True: held now, or already). Where the slots
        cannot be used (another user's directory, a read-only temporary directory) the suite
        runs as it did without them: True, holding none."""
        if self._held is not None:
            return True
        try:
            self._open_directory()
            fds = [os.open(self.directory / f"{i}.lock", os.O_RDONLY | os.O_CREAT, 0o644)
                   for i in range(self.n)]
        except OSError:
            self._held = NONE
            return True
        for fd in fds:  # the first free one is kept, the other descriptors closed
            if self._held is None:
                try:
                    fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
                    self._held = fd
                    continue
                except BlockingIOError:
                    pass
            os.close(fd)
        return self._held is not None

    def _open_directory(self) -> None:
        """The slots' directory, made open to every user of the machine (as ``/tmp`` is) so
        that their suites share it."""
        try:
            self.directory.mkdir(parents=True)
        except FileExistsError:
            return
        self.directory.chmod(0o1777)

    def acquire(self) -> None:
        """Take a slot, waiting for one (the test's time limit paused meanwhile)."""
        if self.try_acquire():
            return
        start = time.monotonic()
        with paused_alarm():
            while not self.try_acquire():
                time.sleep(POLL_S)
        self.waited_s += time.monotonic() - start

    def release(self) -> None:
        if self._held is not None and self._held != NONE:
            os.close(self._held)  # closing the descriptor releases its flock
        self._held = None


@contextlib.contextmanager
def paused_alarm() -> Iterator[None]:
    """Stop the process's ``ITIMER_REAL`` (pytest-timeout's limit) and give it back its time
    left afterwards: the time inside does not count."""
    left, interval = signal.setitimer(signal.ITIMER_REAL, 0)
    try:
        yield
    finally:
        if left > 0:
            signal.setitimer(signal.ITIMER_REAL, left, interval)
