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
after every event that changed the fold, rebuilding only the parts whose sections of the fold
changed (``Parts``). It folds nothing itself: what the page shows is what the stream said,
folded once, for the page and ``/diagnostics`` alike.
"""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path
from typing import Any, TypeVar, cast

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

T = TypeVar("T")


class Parts:
    """The parts of the page's status, each rebuilt only when a section of the fold it reads
    changed (``EventFold.sections``): a channel sample, most of the stream, rebuilds the
    channels and nothing else."""

    def __init__(self, fold: EventFold) -> None:
        self.fold = fold
        self._cache: dict[str, tuple[tuple[int, ...], Any]] = {}

    def get(self, name: str, sections: tuple[str, ...], make: Callable[[], T]) -> T:
        seen = tuple(self.fold.sections[s] for s in sections)
        hit = self._cache.get(name)
        if hit is None or hit[0] != seen:
            hit = self._cache[name] = (seen, make())
        return cast(T, hit[1])


def page_status(fold: EventFold, robot: str = "", parts: Parts | None = None) -> Status:
    """The page's ``Status`` of what ``fold`` holds (its ``version`` is the source's)."""
    part = (parts or Parts(fold)).get
    run = fold.run
    return Status(
        channels=part("channels", ("channels",), lambda: tuple(
            ChannelView(c.id, c.name, c.on, c.state, c.current_ma,
                        tuple(fold.history.get(c.name, ())))
            for c in (fold.channels.channels if fold.channels is not None else ()))),
        observations=part("observations", ("observations",), lambda: dict(fold.observations)),
        diagnoses=part("diagnoses", ("diagnosis",), lambda: tuple(
            DiagnosisStatus(bad, p)
            for bad, p in zip(fold.diagnoses, fold.probabilities(), strict=True) if bad)),
        diagnosis_complete=fold.diagnosis.complete if fold.diagnosis is not None else True,
        unknown=fold.unknown,
        diagnosed_at=fold.diagnosed_at,
        repairs=part("repairs", ("actions",), lambda: tuple(
            RepairStatus(a.record.action, tuple(a.record.args), str(a.record.state),
                         a.started_wall, a.finished_wall) for a in fold.actions.values())),
        board_link_up=fold.link_up,
        board_key=fold.board_key,
        updated=fold.updated,
        robot=robot,
        observation_changes=fold.observation_changes,
        diagnosis_runs=fold.diagnosis_runs,
        diagnosis_latency_sum_s=fold.diagnosis_latency_sum_s,
        diagnosis_last_latency_s=fold.diagnosis_last_latency_s,
        repairs_by_outcome=part("outcomes", ("outcomes",),
                                lambda: dict(fold.repairs_by_outcome)),
        quarantined=part("quarantined", ("excluded",), lambda: fold.quarantined),
        held=part("held", ("excluded",), lambda: fold.held),
        out_of_repair=part("out_of_repair", ("excluded", "run"), lambda: tuple(
            OutOfRepair(x.component, x.state, x.reason, x.by, x.since, release(fold, x),
                        x.safe_state) for x in fold.out_of_repair())),
        run_id=run.run_id if run is not None else "",
        healthy=part("healthy", ("run",), lambda: dict(run.healthy) if run is not None else {}),
        mission=part("mission", ("mission",),
                     lambda: fold.mission_status.to_json() if fold.mission_seen else {}),
        journal_problem=fold.journal.problem,
        journal_held=fold.journal.held,
        journal_dropped=fold.journal.dropped,
        loop_lag_s=fold.lag.lag_s,
        loop_behind=fold.lag.behind,
    )


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
    """Keeps ``source`` equal to ``page_status(fold)``; ``fold`` is read, never fed, here."""

    def __init__(self, source: MemoryStatusSource, fold: EventFold) -> None:
        self.source = source
        self.fold = fold
        self.robot = source.snapshot().robot
        self.parts = Parts(fold)
        fold.listeners.append(self)

    def __call__(self, stamped: Stamped) -> None:
        """The fold changed with ``stamped``: show the new status (``updated``: its time)."""
        self.source.set(page_status(self.fold, self.robot, self.parts))
