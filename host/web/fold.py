"""The page's status as a projection of the one fold of the daemon's event stream.

``page_status(fold, robot)`` reads an ``EventFold`` (``host.fold``) into the page's ``Status``:
the channels with their sparkline histories, the observed literals, the current diagnoses with
their probabilities, the recent repair actions (wall times, in the order they started), the
board link, the run (its id, and the healthy value of each observable atom, by which the page
colours observations), the components out of automatic repair, each with what a person does to
release it (the command, with the run's operator socket when it is not the default, or for a
channel a person switched off, switching it on again), the running counters that ``/metrics``
exports, the journal's health, the daemon's lag and the mission. ``PageProjection(source,
fold)`` keeps a ``MemoryStatusSource`` equal to it: a listener of the fold, it sets a new status
after every event that changed the fold, rebuilding only the fields whose sections of the fold
changed (``FIELDS``: each field, the sections it reads and how). It folds nothing itself: what
the page shows is what the stream said, folded once, for the page and ``/diagnostics`` alike.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable
from pathlib import Path
from typing import Any

from host.events import Stamped
from host.fold import EventFold, Exclusion
from host.operator.client import DEFAULT_SOCKET
from host.web.status import (
    ChannelView,
    DiagnosisStatus,
    MemoryStatusSource,
    OutOfRepair,
    RepairStatus,
    Status,
)


def _channels(f: EventFold) -> tuple[ChannelView, ...]:
    return tuple(ChannelView(c.id, c.name, c.on, c.state, c.current_ma,
                             tuple(f.history.get(c.name, ())))
                 for c in (f.channels.channels if f.channels is not None else ()))


def _diagnoses(f: EventFold) -> tuple[DiagnosisStatus, ...]:
    return tuple(DiagnosisStatus(bad, p)
                 for bad, p in zip(f.diagnoses, f.probabilities(), strict=True) if bad)


def _repairs(f: EventFold) -> tuple[RepairStatus, ...]:
    return tuple(RepairStatus(a.record.action, tuple(a.record.args), str(a.record.state),
                              a.started_wall, a.finished_wall) for a in f.actions.values())


def _out_of_repair(f: EventFold) -> tuple[OutOfRepair, ...]:
    return tuple(OutOfRepair(x.component, x.state, x.reason, x.by, x.since, release(f, x),
                             x.safe_state) for x in f.out_of_repair())


# each field of the page's Status: the sections of the fold it reads, and how
FIELDS: dict[str, tuple[tuple[str, ...], Callable[[EventFold], Any]]] = {
    "channels": (("channels",), _channels),
    "observations": (("observations",), lambda f: dict(f.observations)),
    "observation_changes": (("observations",), lambda f: f.observation_changes),
    "diagnoses": (("diagnosis",), _diagnoses),
    "diagnosis_complete": (("diagnosis",),
                           lambda f: f.diagnosis.complete if f.diagnosis is not None else True),
    "unknown": (("diagnosis",), lambda f: f.unknown),
    "diagnosed_at": (("diagnosis", "runs"), lambda f: f.diagnosed_at),
    "diagnosis_runs": (("runs",), lambda f: f.diagnosis_runs),
    "diagnosis_latency_sum_s": (("runs",), lambda f: f.diagnosis_latency_sum_s),
    "diagnosis_last_latency_s": (("runs",), lambda f: f.diagnosis_last_latency_s),
    "repairs": (("actions",), _repairs),
    "repairs_by_outcome": (("outcomes",), lambda f: dict(f.repairs_by_outcome)),
    "board_link_up": (("link",), lambda f: f.link_up),
    "board_key": (("link",), lambda f: f.board_key),
    "quarantined": (("excluded",), lambda f: f.quarantined),
    "held": (("excluded",), lambda f: f.held),
    "out_of_repair": (("excluded", "run"), _out_of_repair),
    "run_id": (("run",), lambda f: f.run.run_id if f.run is not None else ""),
    "healthy": (("run",), lambda f: dict(f.run.healthy) if f.run is not None else {}),
    "mission": (("mission",), lambda f: f.mission_status.to_json() if f.mission_seen else {}),
    "journal_problem": (("journal",), lambda f: f.journal.problem),
    "journal_held": (("journal",), lambda f: f.journal.held),
    "journal_dropped": (("journal",), lambda f: f.journal.dropped),
    "loop_lag_s": (("lag",), lambda f: f.lag.lag_s),
    "loop_behind": (("lag",), lambda f: f.lag.behind),
}


def page_status(fold: EventFold, robot: str = "") -> Status:
    """The page's ``Status`` of what ``fold`` holds (its ``version`` is the source's)."""
    return Status(robot=robot, updated=fold.updated,
                  **{name: make(fold) for name, (_, make) in FIELDS.items()})


def release(fold: EventFold, x: Exclusion) -> str:
    """What a person does to give ``x.component`` back to automatic repair."""
    run = fold.run
    op = "" if run is None or not run.operator or Path(run.operator) == DEFAULT_SOCKET \
        else f" --operator {run.operator}"
    if x.state == "quarantined":
        return f"dxboard quarantine clear {x.component}{op}"
    command = f"dxboard hold release {x.component}{op}"
    if x.by == "board":  # a person switched its channel off: switching it on releases it
        board = run.board if run is not None and run.board else "BOARD_URL"
        return f"switch it on again (dxboard board {board} on {x.component}), or {command}"
    return command


class PageProjection:
    """Keeps ``source`` equal to ``page_status(fold)``; ``fold`` is read, never fed, here.
    After each change it rebuilds only the fields whose sections of the fold changed."""

    def __init__(self, source: MemoryStatusSource, fold: EventFold) -> None:
        self.source = source
        self.fold = fold
        self.robot = source.snapshot().robot
        self._seen: dict[str, int] = {}
        source.set(page_status(fold, self.robot))
        self._seen = dict(fold.sections)
        fold.listeners.append(self)

    def __call__(self, stamped: Stamped) -> None:
        """The fold changed with ``stamped``: show the new status (``updated``: its time)."""
        now = self.fold.sections
        changed = {s for s, n in now.items() if self._seen.get(s) != n}
        self._seen = dict(now)
        fields = {name: make(self.fold) for name, (sections, make) in FIELDS.items()
                  if not changed.isdisjoint(sections)}
        self.source.set(dataclasses.replace(self.source.snapshot(), updated=self.fold.updated,
                                            **fields))
