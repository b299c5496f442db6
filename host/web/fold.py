"""The page's status as a fold of the daemon's event stream.

``StatusFold(source)`` is a reader of the daemon's event stream (``host.daemon.stream``): each
``Stamped`` event changes the ``Status`` its ``MemoryStatusSource`` holds — the channels (from
``ChannelSample``, with a short history of currents per channel for the sparklines), the
observed literals (``Observation``), the current diagnoses (``DiagnosisRecord``), the repair
actions of the recent plans (``ActionRecord``, their times turned into wall time with the
event's own stamp; in the order they started), the board link (``LinkChange``), the run
(``RunStarted``: its id, and the healthy value of each observable atom, by which the page
colours observations), quarantines and holds (``QuarantineChange``, ``HoldChange``: each with
what a person does to release it — the command, with the run's operator socket when it is not
the default, or for a channel a person switched off, switching it on again), the running
counters that ``/metrics`` exports (``DiagnosisRun``, ``RepairEnded``, changes), the journal's
health (``JournalHealth``: a full disk, the entries held), and the
mission of paper 001's layers (``host.web.mission``: plan, current action, tree status, KB
changes). Nothing else feeds the page: what the page shows is what the stream said, folded.
"""

from __future__ import annotations

import dataclasses
from collections import Counter, deque
from pathlib import Path
from typing import Any

from host.events import (
    ActionRecord,
    ChannelSample,
    DiagnosisRecord,
    DiagnosisRun,
    HoldChange,
    JournalHealth,
    LinkChange,
    LoopLag,
    Observation,
    QuarantineChange,
    RepairEnded,
    RunStarted,
    Stamped,
)
from host.operator.client import DEFAULT_SOCKET
from host.web.mission import MissionFold
from host.web.status import (
    ChannelView,
    DiagnosisStatus,
    MemoryStatusSource,
    OutOfRepair,
    RepairStatus,
    Status,
)

HISTORY = 120  # sparkline points per channel
RECENT_ACTIONS = 30


# the page's fold of the event stream; host/ros/status.py has /diagnostics' (scripts/names.py)
class StatusFold:
    def __init__(self, source: MemoryStatusSource) -> None:
        self.source = source
        self._history: dict[str, deque[float]] = {}
        self._actions: dict[str, RepairStatus] = {}  # by action id, oldest first
        self._outcomes: Counter[str] = Counter()
        self._observations: dict[str, bool | None] = {}
        self._run: RunStarted | None = None
        self._mission = MissionFold()

    def __call__(self, stamped: Stamped) -> None:
        e = stamped.event
        status = self.source.snapshot()
        changes: dict[str, Any] = {}
        if isinstance(e, ChannelSample):
            changes["channels"] = self._channels(e)
        elif isinstance(e, Observation):
            self._observations[e.literal] = e.value
            changes["observations"] = dict(self._observations)
            changes["observation_changes"] = status.observation_changes + 1
        elif isinstance(e, DiagnosisRecord):
            changes["diagnoses"] = tuple(
                DiagnosisStatus(bad, p)
                for bad, p in zip(e.diagnoses, self._probabilities(e), strict=True) if bad)
            changes["diagnosis_complete"] = e.complete
            changes["unknown"] = e.unknown
        elif isinstance(e, DiagnosisRun):
            changes["diagnosis_runs"] = status.diagnosis_runs + 1
            changes["diagnosed_at"] = stamped.wall
            changes["diagnosis_latency_sum_s"] = status.diagnosis_latency_sum_s + e.elapsed_s
            changes["diagnosis_last_latency_s"] = e.elapsed_s
        elif isinstance(e, ActionRecord):
            changes["repairs"] = self._action(e, stamped)
        elif isinstance(e, LinkChange):
            changes["board_link_up"] = e.up
            if e.up:
                changes["board_key"] = e.key
        elif isinstance(e, RepairEnded):
            self._outcomes[e.outcome] += 1
            changes["repairs_by_outcome"] = dict(self._outcomes)
        elif isinstance(e, RunStarted):
            self._run = e
            changes["run_id"] = e.run_id
            changes["healthy"] = dict(e.healthy)
        elif isinstance(e, JournalHealth):
            changes.update(journal_problem=e.problem, journal_held=e.held,
                           journal_dropped=e.dropped)
        elif isinstance(e, LoopLag):
            changes.update(loop_lag_s=e.lag_s, loop_behind=e.behind)
        elif isinstance(e, QuarantineChange | HoldChange):
            changes.update(self._out_of_repair(e, status, stamped.wall))
        elif (mission := self._mission(e)) is not None:
            changes["mission"] = mission.to_json()
        else:
            return
        self.source.set(dataclasses.replace(status, updated=stamped.wall, **changes))

    def _out_of_repair(self, e: QuarantineChange | HoldChange, status: Status,
                       wall: float) -> dict[str, Any]:
        quarantine = isinstance(e, QuarantineChange)
        state = "quarantined" if quarantine else "held"
        now_set = e.quarantined if isinstance(e, QuarantineChange) else e.held
        simple = {k: v for k, v in (status.quarantined if quarantine else status.held).items()
                  if k != e.component}
        rows = [r for r in status.out_of_repair
                if not (r.component == e.component and r.state == state)]
        if now_set:
            simple[e.component] = e.reason
            rows.append(OutOfRepair(e.component, state, e.reason, e.by, wall,
                                    self._release(e),
                                    e.safe_state if isinstance(e, QuarantineChange) else ""))
        return {state: simple, "out_of_repair": tuple(rows)}

    def _release(self, e: QuarantineChange | HoldChange) -> str:
        """What a person does to give ``e.component`` back to automatic repair."""
        run = self._run
        op = "" if run is None or not run.operator or Path(run.operator) == DEFAULT_SOCKET \
            else f" --operator {run.operator}"
        if isinstance(e, QuarantineChange):
            return f"dxboard quarantine clear {e.component}{op}"
        command = f"dxboard hold release {e.component}{op}"
        if e.by == "board":  # a person switched its channel off: switching it on releases it
            board = run.board if run is not None and run.board else "BOARD_URL"
            return f"switch it on again (dxboard board {board} on {e.component}), or {command}"
        return command

    @staticmethod
    def _probabilities(e: DiagnosisRecord) -> list[float | None]:
        if len(e.probabilities) == len(e.diagnoses):
            return list(e.probabilities)
        return [None] * len(e.diagnoses)

    def _channels(self, e: ChannelSample) -> tuple[ChannelView, ...]:
        out = []
        for c in e.channels:
            history = self._history.setdefault(c.name, deque(maxlen=HISTORY))
            history.append(c.current_ma)
            out.append(ChannelView(c.id, c.name, c.on, c.state, c.current_ma, tuple(history)))
        return tuple(out)

    def _action(self, e: ActionRecord, stamped: Stamped) -> tuple[RepairStatus, ...]:
        def wall(mono: float | None) -> float | None:
            return None if mono is None else stamped.wall - (stamped.mono - mono)

        self._actions[e.action_id] = RepairStatus(  # a known id keeps its place
            e.action, tuple(e.args), str(e.state), wall(e.started), wall(e.finished))
        while len(self._actions) > RECENT_ACTIONS:
            del self._actions[next(iter(self._actions))]
        return tuple(self._actions.values())
