"""The daemon's event stream: every event once, stamped with the daemon's times, to every reader.

``EventStream(clock, wall)`` is the one way out of the daemon: the board task, the observers'
sink, the diagnosis runner and the repair service ``emit`` typed events (``host.events``), and
the stream stamps each with the daemon's wall and monotonic times and hands the ``Stamped``
value to every reader in the order they subscribed. The readers: the journal keeps the
journaled kinds, one ``host.fold.EventFold`` folds them into the present state that the web
page and the ROS 2 ``/diagnostics`` publisher project, the terminal prints a line for the ones
a person must see. A reader that raises is logged and never stops the stream or
the others (a broken page must not stop a repair). ``emit`` runs on the daemon's loop thread.
"""

from __future__ import annotations

import logging
import time
from collections.abc import Callable

from host.events import Event, Stamped

log = logging.getLogger(__name__)

Reader = Callable[[Stamped], None]


class EventStream:
    def __init__(self, clock: Callable[[], float] = time.monotonic,
                 wall: Callable[[], float] = time.time) -> None:
        self.clock = clock
        self.wall = wall
        self._readers: list[Reader] = []

    def subscribe(self, reader: Reader) -> Callable[[], None]:
        """Add a reader; returns the function that removes it."""
        self._readers.append(reader)
        return lambda: self._readers.remove(reader) if reader in self._readers else None

    def emit(self, event: Event) -> None:
        stamped = Stamped(self.wall(), self.clock(), event)
        for reader in list(self._readers):
            try:
                reader(stamped)
            except Exception:
                log.exception("a reader of the event stream failed on %s", type(event).__name__)

    def wall_of(self, mono: float | None) -> float | None:
        """A time of the daemon's monotonic clock as wall time."""
        if mono is None:
            return None
        return self.wall() - (self.clock() - mono)
