"""The journal: an append-only SQLite (WAL) record of what the daemon saw, thought and did.

Every observation change, diagnosis, plan, repair action and result, board event, downsampled
telemetry and note is an ``Entry`` with a monotonic id and the daemon's wall and monotonic
times (``entries``). ``Journal`` writes from a background thread so the asyncio loop never
waits for the disk (``writer``); ``JournalReader`` answers tail / since-id / by-kind /
time-range queries for the web page, ``dxboard journal`` and the timeline report (``store``);
``TelemetryDownsampler`` turns 100 Hz channel readings into the 1 Hz summaries that are
journaled (``telemetry``).
"""

from host.events import (
    ActionRecord,
    ActionState,
    BoardEvent,
    ChannelSummary,
    DiagnosisRecord,
    HoldChange,
    Kind,
    LinkChange,
    Note,
    Observation,
    Payload,
    PlanRecord,
    PlanStep,
    QuarantineChange,
    RepairEnded,
    RunStarted,
    Telemetry,
)
from host.journal.entries import Entry
from host.journal.store import JournalReader
from host.journal.telemetry import TelemetryDownsampler
from host.journal.writer import Journal, Retention

__all__ = [
    "ActionRecord",
    "ActionState",
    "BoardEvent",
    "ChannelSummary",
    "DiagnosisRecord",
    "Entry",
    "HoldChange",
    "Journal",
    "JournalReader",
    "Kind",
    "LinkChange",
    "Note",
    "Observation",
    "Payload",
    "PlanRecord",
    "PlanStep",
    "QuarantineChange",
    "RepairEnded",
    "Retention",
    "RunStarted",
    "Telemetry",
    "TelemetryDownsampler",
]
