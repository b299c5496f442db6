"""Telling the rest of the daemon that its journal cannot write: a ``JournalHealth`` event.

The journal's writer (``host.journal.writer``) holds entries in memory while commits fail (a
full disk) and writes them when it can; it says so on the terminal itself. ``watch(journal,
emit)`` is the daemon task that tells everyone else: it reads ``journal.health()`` every
``PERIOD_S`` and emits ``JournalHealth`` on the event stream when the problem appears or goes,
and, while it lasts, when the number of entries held changed (at most once per
``RECOUNT_S``), so the page, ``/api/status`` (``host.web.fold``, ``host.web.headline``) and
``/diagnostics`` (``host.ros.status``: ``dxboard/daemon``) say "journal: disk full, N entries
held" and then that it writes again. Polling, not a callback from the writer's thread: the
writer never waits for the loop, and the loop never waits for the disk.
"""

from __future__ import annotations

import asyncio
import time
from collections.abc import Callable
from typing import Protocol

from host.events import Event, JournalHealth

PERIOD_S = 0.25
RECOUNT_S = 1.0


class Health(Protocol):
    def health(self) -> tuple[str, int, int]: ...


async def watch(journal: Health, emit: Callable[[Event], None], *,
                clock: Callable[[], float] = time.monotonic) -> None:
    """Emit ``JournalHealth`` on every change of the journal's health (see the docstring)."""
    said = ("", 0, 0)
    said_at = 0.0
    while True:
        await asyncio.sleep(PERIOD_S)
        now = journal.health()
        problem, _held, dropped = now
        changed = problem != said[0] or dropped != said[2]
        recount = problem and now != said and clock() - said_at >= RECOUNT_S
        if changed or recount:
            emit(JournalHealth(*now) if problem else JournalHealth("", 0, dropped))
            said, said_at = now if problem else ("", 0, dropped), clock()
