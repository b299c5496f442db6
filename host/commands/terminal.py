"""What ``dxboard run`` says on its terminal: one line per thing a person must know, as it happens.

``TerminalLines(write)`` is a reader of the daemon's event stream: it prints, with the local time,
the run's id (``dxboard report --run ID`` draws it), every change of diagnosis, every repair
plan, every finished repair step (succeeded, failed, timed out), how each repair ended, every
quarantine and hold (set or cleared), the board link going down or coming back, and the
daemon's warnings and errors. Observations, telemetry and the
steps' ``started`` states are left to the journal and the page (``dxboard run -q`` prints none
of it). Each line is ``host.events.describe`` of the event: the journal and the page say the
same words. ``paused=True`` queues the lines until ``resume()`` (``dxboard run`` prints its URLs
first). A terminal nobody reads (a full pipe, a paused pager) must never stall the daemon:
lines go through a bounded queue to a writer thread, and when it is full a line is dropped and
counted (the count is said with the next line that gets through).
"""

from __future__ import annotations

import contextlib
import queue
import sys
import threading
import time
from collections.abc import Callable

from host.events import (
    ActionRecord,
    ActionState,
    DiagnosisRecord,
    HoldChange,
    LinkChange,
    Note,
    PlanRecord,
    QuarantineChange,
    RepairEnded,
    RunStarted,
    Stamped,
    describe,
)

_ALWAYS = (RunStarted, DiagnosisRecord, PlanRecord, RepairEnded, QuarantineChange, HoldChange,
           LinkChange)


def _stdout(line: str) -> None:
    print(line, file=sys.stdout, flush=True)


class TerminalLines:
    def __init__(self, write: Callable[[str], None] = _stdout, backlog: int = 1000, *,
                 paused: bool = False) -> None:
        self.write = write
        self.dropped = 0
        self._go = threading.Event()
        if not paused:
            self._go.set()
        self._queue: queue.Queue[str | None] = queue.Queue(backlog)
        self._thread = threading.Thread(target=self._writer, name="terminal", daemon=True)
        self._thread.start()

    def __call__(self, s: Stamped) -> None:
        e = s.event
        if isinstance(e, _ALWAYS) or (
                isinstance(e, ActionRecord) and e.state is not ActionState.STARTED) or (
                isinstance(e, Note) and e.level != "info"):
            stamp = time.strftime("%H:%M:%S", time.localtime(s.wall))
            line = f"{stamp} {self.label(e)}{describe(e)}"
            if self.dropped:
                line += f"  ({self.dropped} earlier line(s) not shown: the terminal was full)"
            try:
                self._queue.put_nowait(line)
                self.dropped = 0
            except queue.Full:
                self.dropped += 1

    def say(self, text: str) -> None:
        """A line of the command's own, stamped now, after the lines queued before it."""
        with contextlib.suppress(queue.Full):
            self._queue.put_nowait(f"{time.strftime('%H:%M:%S')} {text}")

    def resume(self) -> None:
        """Start writing (a paused terminal queues its lines until then)."""
        self._go.set()

    def _writer(self) -> None:
        self._go.wait()
        while (line := self._queue.get()) is not None:
            try:
                self.write(line)
            except (OSError, ValueError):  # the terminal went away: stop writing
                return

    def close(self, timeout: float = 2.0) -> None:
        """Write what is queued (within ``timeout``) and stop the writer."""
        self._go.set()
        try:
            self._queue.put(None, timeout=timeout)
        except queue.Full:
            return
        self._thread.join(timeout)

    @staticmethod
    def label(e: object) -> str:
        if isinstance(e, DiagnosisRecord):
            return "diagnosis: "
        if isinstance(e, ActionRecord):
            return "step: "
        return ""
