"""What ``dxboard run`` says on its terminal: one line per thing a person must know, as it happens.

``TerminalLines(write)`` is a reader of the daemon's event stream: it prints, with the local time,
every change of diagnosis, every repair plan, every finished repair step (succeeded, failed,
timed out), how each repair ended, every quarantine and hold (set or cleared), the board link
going down or coming back, and the daemon's warnings and errors. Observations, telemetry and the
steps' ``started`` states are left to the journal and the page (``dxboard run -q`` prints none
of it). Each line is ``host.events.describe`` of the event: the journal and the page say the
same words.
"""

from __future__ import annotations

import sys
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
    Stamped,
    describe,
)

_ALWAYS = (DiagnosisRecord, PlanRecord, RepairEnded, QuarantineChange, HoldChange, LinkChange)


def _stdout(line: str) -> None:
    print(line, file=sys.stdout, flush=True)


class TerminalLines:
    def __init__(self, write: Callable[[str], None] = _stdout) -> None:
        self.write = write

    def __call__(self, s: Stamped) -> None:
        e = s.event
        if isinstance(e, _ALWAYS) or (
                isinstance(e, ActionRecord) and e.state is not ActionState.STARTED) or (
                isinstance(e, Note) and e.level != "info"):
            stamp = time.strftime("%H:%M:%S", time.localtime(s.wall))
            self.write(f"{stamp} {self.label(e)}{describe(e)}")

    @staticmethod
    def label(e: object) -> str:
        if isinstance(e, DiagnosisRecord):
            return "diagnosis: "
        if isinstance(e, ActionRecord):
            return "step: "
        return ""
