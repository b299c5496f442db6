"""What the web page shows, as typed values, and the interface the daemon implements to feed it.

``Status`` is one immutable snapshot of what the daemon knows: the board's channels (state,
current and a short history of currents for the sparkline), the observed literals (True, False,
or None when unknown) and the value of each that is healthy (as the model entails it, so the
page colours by health, not truth), the current minimal diagnoses, the repair actions of the
current and recent plans (in the order they started), the components out of automatic repair
(quarantined or held, with what a person does to release each), whether the board link is up,
the daemon run, whether the journal can write (and what it holds in memory until it can),
the wall time of the newest data in it, and the running counters that
``/metrics`` exports. ``StatusSource`` is the whole contract between the
daemon and the web server: ``snapshot()`` returns the latest ``Status`` and ``wait_changed``
waits (on the daemon's loop) until a newer one exists. ``MemoryStatusSource`` is a complete
implementation that holds a status and lets its owner replace or update it; the daemon's
``PageProjection`` (``host.web.fold``) sets it from the one fold of the event stream, and the
tests drive the page with it. The server
never reads anything else from the daemon; times are the daemon's (``updated``), never read
here.
"""

from __future__ import annotations

import asyncio
import dataclasses
import logging
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any, Protocol

from protocol.constants import STATE_NAMES

log = logging.getLogger(__name__)

# the firmware's channel states, for the page's colours and the metrics
CHANNEL_STATES: tuple[str, ...] = tuple(STATE_NAMES)


@dataclass(frozen=True)
class ChannelView:
    id: int
    name: str
    on: bool
    state: str
    current_ma: float
    history_ma: tuple[float, ...] = ()  # recent currents, oldest first, for the sparkline

    def to_json(self) -> dict[str, Any]:
        return {"id": self.id, "name": self.name, "on": self.on, "state": self.state,
                "current_ma": self.current_ma, "history_ma": list(self.history_ma)}


@dataclass(frozen=True)
class DiagnosisStatus:
    bad: tuple[str, ...]
    probability: float | None = None

    def to_json(self) -> dict[str, Any]:
        return {"bad": list(self.bad), "probability": self.probability}


@dataclass(frozen=True)
class RepairStatus:
    action: str
    args: tuple[str, ...]
    state: str  # started | succeeded | failed | timeout (| planned, not started yet)
    started: float | None
    finished: float | None = None

    def to_json(self) -> dict[str, Any]:
        return {"action": self.action, "args": list(self.args), "state": self.state,
                "started": self.started, "finished": self.finished}


@dataclass(frozen=True)
class OutOfRepair:
    """A component no repair touches (``state``: quarantined or held) until a person releases
    it: how (``release``, e.g. ``dxboard quarantine clear hokuyo``), since when (wall time)."""

    component: str
    state: str  # quarantined | held
    reason: str
    by: str
    since: float
    release: str
    safe_state: str = ""

    def to_json(self) -> dict[str, Any]:
        return dataclasses.asdict(self)


@dataclass(frozen=True)
class Status:
    """One snapshot; ``version`` grows with every change (the source sets it)."""

    channels: tuple[ChannelView, ...] = ()
    observations: Mapping[str, bool | None] = field(default_factory=dict)
    diagnoses: tuple[DiagnosisStatus, ...] = ()
    diagnosis_complete: bool = True
    unknown: tuple[str, ...] = ()  # components whose observations expired (not healthy)
    diagnosed_at: float = 0.0  # wall time of the daemon's last diagnosis (0: none yet)
    repairs: tuple[RepairStatus, ...] = ()
    board_link_up: bool = False
    board_key: str = ""  # what the board said of the daemon's key (``LinkChange.key``)
    updated: float = 0.0  # wall time (daemon's clock) of the newest data in this snapshot
    robot: str = ""
    # running counters for /metrics
    observation_changes: int = 0
    diagnosis_runs: int = 0
    diagnosis_latency_sum_s: float = 0.0
    diagnosis_last_latency_s: float | None = None
    repairs_by_outcome: Mapping[str, int] = field(default_factory=dict)
    # components out of automatic repair: name -> why (quarantined by the daemon or a person;
    # held by a person for maintenance)
    quarantined: Mapping[str, str] = field(default_factory=dict)
    held: Mapping[str, str] = field(default_factory=dict)
    out_of_repair: tuple[OutOfRepair, ...] = ()  # the same, in detail, in the order set
    run_id: str = ""
    healthy: Mapping[str, bool] = field(default_factory=dict)  # atom -> its healthy value
    mission: Mapping[str, Any] = field(default_factory=dict)  # host.fold.mission, as JSON
    # the journal: why it cannot write ("" while it does, e.g. "disk full"), the entries it
    # holds in memory until it can, and those it lost beyond its bound
    journal_problem: str = ""
    journal_held: int = 0
    journal_dropped: int = 0
    # the daemon behind: its event loop's lag (s, host.daemon.lagwatch) and whether it is over
    # the limit
    loop_lag_s: float = 0.0
    loop_behind: bool = False
    version: int = 0

    def to_json(self) -> dict[str, Any]:
        return {
            "version": self.version,
            "robot": self.robot,
            "run_id": self.run_id,
            "updated": self.updated,
            "board_link_up": self.board_link_up,
            "board_key": self.board_key,
            "channels": [c.to_json() for c in self.channels],
            "observations": dict(sorted(self.observations.items())),
            "healthy": dict(sorted(self.healthy.items())),
            "diagnoses": [d.to_json() for d in self.diagnoses],
            "diagnosis_complete": self.diagnosis_complete,
            "unknown": list(self.unknown),
            "diagnosed_at": self.diagnosed_at,
            "repairs": [r.to_json() for r in self.repairs],
            "quarantined": dict(sorted(self.quarantined.items())),
            "held": dict(sorted(self.held.items())),
            "out_of_repair": [o.to_json() for o in self.out_of_repair],
            "mission": dict(self.mission),
            "journal": {"problem": self.journal_problem, "held": self.journal_held,
                        "dropped": self.journal_dropped},
            "daemon": {"loop_lag_s": self.loop_lag_s, "behind": self.loop_behind},
            "counters": {
                "observation_changes": self.observation_changes,
                "diagnosis_runs": self.diagnosis_runs,
                "diagnosis_latency_sum_s": self.diagnosis_latency_sum_s,
                "diagnosis_last_latency_s": self.diagnosis_last_latency_s,
                "repairs_by_outcome": dict(self.repairs_by_outcome),
            },
        }


class StatusSource(Protocol):
    """What the daemon gives the web server."""

    def snapshot(self) -> Status:
        """The latest status (cheap: called on every request and push)."""
        ...

    async def wait_changed(self, version: int) -> Status:
        """Return the latest status as soon as its ``version`` differs from ``version``."""
        ...


class MemoryStatusSource:
    """A ``StatusSource`` holding one status in memory; change it with ``set`` or ``update``.

    Call it from the event loop's thread (the daemon's loop); waiters wake on every change.
    """

    def __init__(self, status: Status | None = None) -> None:
        self._status = dataclasses.replace(status or Status(), version=1)
        self._changed = asyncio.Event()

    def snapshot(self) -> Status:
        return self._status

    async def wait_changed(self, version: int) -> Status:
        while self._status.version == version:
            event = self._changed
            await event.wait()
        return self._status

    def set(self, status: Status) -> Status:
        """Replace the whole status (its ``version`` is overwritten)."""
        self._status = dataclasses.replace(status, version=self._status.version + 1)
        event, self._changed = self._changed, asyncio.Event()
        event.set()
        return self._status

    def update(self, **changes: Any) -> Status:
        """Change some fields of the status, e.g. ``update(board_link_up=False)``."""
        return self.set(dataclasses.replace(self._status, **changes))

    def update_channel(self, channel_id: int, *, history_len: int = 120,
                       **changes: Any) -> Status:
        """Change one channel; a new ``current_ma`` is also appended to its history."""
        channels = []
        for c in self._status.channels:
            if c.id == channel_id:
                if "current_ma" in changes and "history_ma" not in changes:
                    history = (*c.history_ma, float(changes["current_ma"]))
                    changes["history_ma"] = history[-history_len:]
                c = dataclasses.replace(c, **changes)
            channels.append(c)
        if all(c.id != channel_id for c in channels):
            raise KeyError(f"no channel {channel_id}")
        return self.update(channels=tuple(channels))
