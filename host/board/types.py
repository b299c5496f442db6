"""The values the board client hands out: board info, state, readings and stream notices.

Each is a frozen dataclass, a typed value on the arrows of ARCHITECTURE.md. A ``Reading`` is one
measurement with everything needed to judge it: the host's receive time (wall clock for people
and journals, monotonic for ages), the board's boot id, sequence number and uptime, and
``missed``, the number of readings lost just before it (a gap in the board's numbering, or
readings the host dropped because a consumer fell behind), so no loss is silent. ``stale``
tells whether it is older than a limit. The subscription stream also carries ``BoardEvent``
(trips, state changes...), ``LinkDown`` / ``LinkUp`` (the link went away and came back) and
``Rebooted`` (the board booted in between: a new boot id, or an uptime that went backwards).
"""

from __future__ import annotations

import time
from dataclasses import dataclass

from protocol.constants import (
    BOARD_CHANNEL,
    BOARD_FLAG_NAMES,
    CAPABILITY_NAMES,
    CONFIG_STATUS_NAMES,
    EV_STATE,
    EVENT_NAMES,
    F_DEADMAN,
    F_SHED_TOTAL,
    F_SHED_UV,
    FAULT_NAMES,
    RESET_NAMES,
    ST_INRUSH,
    ST_OFF,
    ST_ON,
    STATE_NAMES,
)
from protocol.events import describe_event, flag_names


def _name(names: tuple[str, ...], i: int) -> str:
    return names[i] if 0 <= i < len(names) and names[i] else f"#{i}"


@dataclass(frozen=True)
class BoardInfo:
    """What the board's HELLO said, plus the transport that reached it."""

    url: str
    scheme: str
    version: int
    board_id: str
    firmware: str
    channels: int
    capabilities: int
    boot_id: int
    reset_cause: int
    config_status: int
    transport_caps: frozenset[str]

    def to_dict(self) -> dict[str, object]:
        return {
            "url": self.url, "scheme": self.scheme, "version": self.version,
            "board_id": self.board_id, "firmware": self.firmware, "channels": self.channels,
            "capabilities": flag_names(self.capabilities, CAPABILITY_NAMES),
            "boot_id": self.boot_id, "reset_cause": _name(RESET_NAMES, self.reset_cause),
            "config_status": _name(CONFIG_STATUS_NAMES, self.config_status),
            "transport": sorted(self.transport_caps),
        }


@dataclass(frozen=True)
class ChannelState:
    channel: int
    name: str
    commanded: bool
    physical: bool
    state: int
    current_ma: int
    live_faults: int
    sticky_faults: int
    trips: int
    retries: int

    @property
    def state_name(self) -> str:
        return _name(STATE_NAMES, self.state)

    def to_dict(self) -> dict[str, object]:
        return {
            "channel": self.channel, "name": self.name, "state": self.state_name,
            "commanded": self.commanded, "physical": self.physical,
            "current_ma": self.current_ma, "live_faults": flag_names(self.live_faults, FAULT_NAMES),
            "sticky_faults": flag_names(self.sticky_faults, FAULT_NAMES), "trips": self.trips,
            "retries": self.retries,
        }


@dataclass(frozen=True)
class BoardState:
    host_time: float
    boot_id: int
    uptime_ms: int
    input_mv: int
    total_ma: int
    reset_cause: int
    config_status: int
    board_flags: int
    channels: tuple[ChannelState, ...]

    @property
    def reset_cause_name(self) -> str:
        return _name(RESET_NAMES, self.reset_cause)

    def to_dict(self) -> dict[str, object]:
        return {
            "host_time": self.host_time, "boot_id": self.boot_id, "uptime_ms": self.uptime_ms,
            "input_mv": self.input_mv, "total_ma": self.total_ma,
            "reset_cause": self.reset_cause_name,
            "config_status": _name(CONFIG_STATUS_NAMES, self.config_status),
            "board_flags": flag_names(self.board_flags, BOARD_FLAG_NAMES),
            "channels": [c.to_dict() for c in self.channels],
        }


@dataclass(frozen=True)
class SwitchResult:
    """A channel read back after switch, power-cycle or clear."""

    channel: int
    name: str
    commanded: bool
    physical: bool
    state: int

    @property
    def state_name(self) -> str:
        return _name(STATE_NAMES, self.state)

    def to_dict(self) -> dict[str, object]:
        return {"channel": self.channel, "name": self.name, "commanded": self.commanded,
                "physical": self.physical, "state": self.state_name}


@dataclass(frozen=True)
class Reading:
    """One measurement of every channel (see the module docstring)."""

    host_time: float
    host_mono: float
    boot_id: int
    seq: int
    uptime_ms: int
    input_mv: int
    on_mask: int
    fault_mask: int
    currents_ma: tuple[int, ...]
    missed: int = 0

    def age(self, now_mono: float | None = None) -> float:
        """Seconds since the host received it."""
        return (time.monotonic() if now_mono is None else now_mono) - self.host_mono

    def stale(self, max_age_s: float, now_mono: float | None = None) -> bool:
        return self.age(now_mono) > max_age_s

    def to_dict(self) -> dict[str, object]:
        return {"host_time": self.host_time, "boot_id": self.boot_id, "seq": self.seq,
                "uptime_ms": self.uptime_ms, "input_mv": self.input_mv,
                "on_mask": self.on_mask, "fault_mask": self.fault_mask,
                "currents_ma": list(self.currents_ma), "missed": self.missed}


# what the board said, as the board client hands it up; host/events.py's BoardEvent is the
# same thing on the daemon's event stream, which this layer may not import (scripts/names.py)
@dataclass(frozen=True)
class BoardEvent:
    host_time: float
    boot_id: int
    seq: int
    uptime_ms: int
    kind: int
    channel: int
    old_state: int
    new_state: int
    faults: int
    value_ma: int
    dropped: int

    @property
    def kind_name(self) -> str:
        return _name(EVENT_NAMES, self.kind)

    def switched(self) -> bool | None:
        """True or False when the channel was switched on or off by a command (not by the
        board's protection: no trip, shed or dead-man), else None."""
        if self.kind != EV_STATE or self.faults & (F_SHED_UV | F_SHED_TOTAL | F_DEADMAN):
            return None
        if self.old_state in (ST_ON, ST_INRUSH) and self.new_state == ST_OFF:
            return False
        if self.old_state == ST_OFF and self.new_state == ST_INRUSH:
            return True
        return None

    def fields(self, channel_names: list[str]) -> dict[str, object]:
        """What the event says, by name, for the journal: the channel's name, its state
        change, its faults and the value that triggered it."""
        if self.channel == BOARD_CHANNEL:  # board flags and millivolts (PROTOCOL.md §4.2)
            said = describe_event(self)
            return {"name": "board", **{k: v for k, v in said.items()
                                        if k not in ("kind", "board")}}
        name = channel_names[self.channel] if self.channel < len(channel_names) else "board"
        return {"name": name, "from": _name(STATE_NAMES, self.old_state),
                "to": _name(STATE_NAMES, self.new_state),
                "faults": flag_names(self.faults, FAULT_NAMES), "value_ma": self.value_ma}

    def to_dict(self) -> dict[str, object]:
        head = {"host_time": self.host_time, "event": self.kind_name, "seq": self.seq,
                "uptime_ms": self.uptime_ms, "channel": self.channel}
        if self.channel == BOARD_CHANNEL:
            said = describe_event(self)
            return {**head, **{k: v for k, v in said.items() if k != "kind"},
                    "dropped": self.dropped}
        return {**head, "old_state": _name(STATE_NAMES, self.old_state),
                "new_state": _name(STATE_NAMES, self.new_state), "faults": self.faults,
                "value_ma": self.value_ma, "dropped": self.dropped}


@dataclass(frozen=True)
class LinkDown:
    """The link was lost; readings stop until ``LinkUp`` (everything known is now stale)."""

    host_time: float
    reason: str


@dataclass(frozen=True)
class LinkUp:
    """The link is back after ``down_s`` seconds."""

    host_time: float
    down_s: float
    info: BoardInfo


@dataclass(frozen=True)
class Rebooted:
    """The board booted since it was last seen."""

    host_time: float
    old_boot_id: int
    new_boot_id: int
    reset_cause: int
    how: str  # "boot id" or "uptime"

    @property
    def reset_cause_name(self) -> str:
        return _name(RESET_NAMES, self.reset_cause)


StreamItem = Reading | BoardEvent | LinkDown | LinkUp | Rebooted
