"""The page's status as a fold of the daemon's event stream.

``StatusFold(source)`` is a reader of the daemon's event stream (``host.daemon.stream``): each
``Stamped`` event changes the ``Status`` its ``MemoryStatusSource`` holds — the channels (from
``ChannelSample``, with a short history of currents per channel for the sparklines), the
observed literals (``Observation``), the current diagnoses (``DiagnosisRecord``), the repair
actions of the recent plans (``ActionRecord``, their times turned into wall time with the
event's own stamp), the board link (``LinkChange``), quarantines and holds, and the running
counters that ``/metrics`` exports (``DiagnosisRun``, ``RepairEnded``, changes), and the mission
of paper 001's layers (``host.web.mission``: plan, current action, tree status, KB changes).
Nothing else feeds the page: what the page shows is what the stream said, folded.
"""

from __future__ import annotations

import dataclasses
from collections import Counter, deque
from typing import Any

from host.events import (
    ActionRecord,
    ChannelSample,
    DiagnosisRecord,
    DiagnosisRun,
    HoldChange,
    LinkChange,
    Observation,
    QuarantineChange,
    RepairEnded,
    Stamped,
)
from host.web.mission import MissionFold
from host.web.status import (
    ChannelStatus,
    DiagnosisStatus,
    MemoryStatusSource,
    RepairStatus,
)

HISTORY = 120  # sparkline points per channel
RECENT_ACTIONS = 30


class StatusFold:
    def __init__(self, source: MemoryStatusSource) -> None:
        self.source = source
        self._history: dict[str, deque[float]] = {}
        self._actions: dict[str, RepairStatus] = {}  # by action id, oldest first
        self._outcomes: Counter[str] = Counter()
        self._observations: dict[str, bool | None] = {}
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
        elif isinstance(e, DiagnosisRun):
            changes["diagnosis_runs"] = status.diagnosis_runs + 1
            changes["diagnosis_latency_sum_s"] = status.diagnosis_latency_sum_s + e.elapsed_s
            changes["diagnosis_last_latency_s"] = e.elapsed_s
        elif isinstance(e, ActionRecord):
            changes["repairs"] = self._action(e, stamped)
        elif isinstance(e, LinkChange):
            changes["board_link_up"] = e.up
        elif isinstance(e, RepairEnded):
            self._outcomes[e.outcome] += 1
            changes["repairs_by_outcome"] = dict(self._outcomes)
        elif isinstance(e, QuarantineChange):
            q = {k: v for k, v in status.quarantined.items() if k != e.component}
            if e.quarantined:
                q[e.component] = e.reason
            changes["quarantined"] = q
        elif isinstance(e, HoldChange):
            h = {k: v for k, v in status.held.items() if k != e.component}
            if e.held:
                h[e.component] = e.reason
            changes["held"] = h
        elif (mission := self._mission(e)) is not None:
            changes["mission"] = mission.to_json()
        else:
            return
        self.source.set(dataclasses.replace(status, updated=stamped.wall, **changes))

    @staticmethod
    def _probabilities(e: DiagnosisRecord) -> list[float | None]:
        if len(e.probabilities) == len(e.diagnoses):
            return list(e.probabilities)
        return [None] * len(e.diagnoses)

    def _channels(self, e: ChannelSample) -> tuple[ChannelStatus, ...]:
        out = []
        for c in e.channels:
            history = self._history.setdefault(c.name, deque(maxlen=HISTORY))
            history.append(c.current_ma)
            out.append(ChannelStatus(c.id, c.name, c.on, c.state, c.current_ma, tuple(history)))
        return tuple(out)

    def _action(self, e: ActionRecord, stamped: Stamped) -> tuple[RepairStatus, ...]:
        def wall(mono: float | None) -> float | None:
            return None if mono is None else stamped.wall - (stamped.mono - mono)

        self._actions.pop(e.action_id, None)
        self._actions[e.action_id] = RepairStatus(
            e.action, tuple(e.args), str(e.state), wall(e.started), wall(e.finished))
        while len(self._actions) > RECENT_ACTIONS:
            del self._actions[next(iter(self._actions))]
        return tuple(self._actions.values())
