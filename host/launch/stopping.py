"""Saying what a stop is waiting for, while it waits.

A clean stop closes many things in turn: the repairs and the nodes they started, the
observers, the topic source, the web page, the journal's last commit, the emulated board. On
a busy machine one of them can take seconds, and a person who pressed Ctrl-C should not have
to guess whether anything is happening. ``Stopping(what).start()`` runs a thread (so it reports even
while the event loop itself is held up) that says every ``every_s`` seconds how long the stop
has taken and what it is waiting for: ``what()``, the stage the closing code last named
(``LaunchedRobot.closing``), until ``done()``.
"""

from __future__ import annotations

import logging
import threading
import time
from collections.abc import Callable

log = logging.getLogger(__name__)

EVERY_S = 5.0


class Stopping:
    def __init__(self, what: Callable[[], str], every_s: float = EVERY_S,
                 report: Callable[[str], None] | None = None) -> None:
        self.what = what
        self.every_s = every_s
        self.report = report or log.warning
        self._done = threading.Event()
        self._thread = threading.Thread(target=self._run, name="stopping", daemon=True)
        self._t0 = 0.0

    def start(self) -> None:
        self._t0 = time.monotonic()
        self._thread.start()

    def done(self) -> None:
        self._done.set()
        if self._thread.is_alive():
            self._thread.join()

    def _run(self) -> None:
        while not self._done.wait(self.every_s):
            self.report(f"still stopping after {time.monotonic() - self._t0:.0f} s: "
                        f"waiting for {self.what()}")
