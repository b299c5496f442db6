"""The daemon's state in ``diagnostic_msgs`` terms: a fold of its event stream into statuses.

``StatusFold(components)`` reads ``Stamped`` events (``host.events``) and keeps what a ROS 2
robot monitor shows; it is pure (no rclpy, no clock), so it is tested on its own and the
publisher (``host.ros.publisher``) only turns its ``Status`` values into messages. Status names
are paths under ``dxboard/`` that the standard ``diagnostic_aggregator`` groups into one tree
(``ros/dxboard_ros/config/analyzers.yaml``; rqt_robot_monitor shows it as it is)::

    dxboard/components/NAME       one per component of the model (hardware_id: the component)
    dxboard/board/link            the board (hardware_id ``board``)
    dxboard/board/channels/NAME   one per board channel (hardware_id ``channel N``)
    dxboard/diagnosis             the minimal diagnoses (hardware_id ``dxboard``)
    dxboard/repair                the latest repair step (hardware_id ``dxboard``)
    dxboard/daemon                the daemon itself (hardware_id ``daemon``)

A component's level::

    level   when
    STALE   no diagnosis yet
    ERROR   abnormal in the best (first) minimal diagnosis, or quarantined
    WARN    abnormal only in other minimal diagnoses (a suspect)
    OK      normal in every minimal diagnosis

with the reason as the message and the key/values ``diagnoses`` (in how many minimal
diagnoses it is abnormal, of how many), ``repair`` (its latest repair action and that action's
state), ``quarantined`` and ``held``. A channel is ERROR when tripped, latched or faulted,
STALE while the link is down (key/values state, on, current_a, last_event); the board link is
OK while up, else ERROR with the reason (key/values link, total_current_a, input_v). The
diagnosis is STALE before the first (or when nothing is found broken but some components went
unobserved), OK when every component is normal, else ERROR with the best diagnosis as the
message (key/values best, diagnoses, all, unknown). The repair is OK with no step yet or the
latest one started or succeeded, ERROR when it failed or timed out (key/values action,
state). The daemon is OK "journal: writing", ERROR "journal: disk full, N entries held"
while its journal cannot write, WARN "behind: its event loop runs N s late" while its loop
lags over 1 s (``host.daemon.lagwatch``; key/values journal, journal_held, journal_dropped,
behind, loop_lag_s). ``diagnoses``, ``currents_a`` and ``input_v`` are the latest minimal
diagnoses, channel currents and the board's input voltage, for ``/diagnosis``,
``/board_measurements`` and ``/battery_state``.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field

from host.events import (
    ActionRecord,
    BoardEvent,
    ChannelSample,
    DiagnosisRecord,
    HoldChange,
    JournalHealth,
    LinkChange,
    LoopLag,
    QuarantineChange,
    Stamped,
    journal_health_text,
    loop_lag_text,
)

OK, WARN, ERROR, STALE = 0, 1, 2, 3
BAD_STATES = ("tripped", "latched", "faulted")
PREFIX = "dxboard"  # the root of every status name: one tree in the aggregator
BAD_ACTION_STATES = ("failed", "timeout")


# a REP-107 DiagnosticStatus; host/web/status.py's Status is the page's: two projections of
# the event stream, each folded by its StatusFold until one fold serves both (issue 26 item 3)
@dataclass(frozen=True)
class Status:
    level: int
    name: str
    message: str
    hardware_id: str
    values: tuple[tuple[str, str], ...] = ()


@dataclass
class _Component:
    repair: str = "none"
    quarantined: str = ""  # the reason, when quarantined
    held: bool = False


# /diagnostics' fold of the event stream; host/web/fold.py has the page's (scripts/names.py)
@dataclass
class StatusFold:
    components: Sequence[str]
    diagnosis: DiagnosisRecord | None = None
    channels: ChannelSample | None = None
    link_up: bool = False
    link_reason: str = "not connected yet"
    _comp: dict[str, _Component] = field(default_factory=dict)
    _last_event: dict[int, str] = field(default_factory=dict)
    journal: JournalHealth = field(default_factory=lambda: JournalHealth(""))
    last_action: ActionRecord | None = None
    lag: LoopLag = field(default_factory=lambda: LoopLag(0.0, False))

    def __post_init__(self) -> None:
        self._comp = {c: _Component() for c in self.components}

    def feed(self, stamped: Stamped) -> bool:
        """Take one event; True when the statuses may have changed."""
        e = stamped.event
        match e:
            case DiagnosisRecord():
                self.diagnosis = e
            case ChannelSample():
                self.channels = e
            case LinkChange():
                self.link_up, self.link_reason = e.up, e.reason
            case ActionRecord():
                self.last_action = e
                for arg in e.args:
                    if arg in self._comp:
                        self._comp[arg].repair = f"{e.action}({', '.join(e.args)}) {e.state}"
            case QuarantineChange() if e.component in self._comp:
                self._comp[e.component].quarantined = (e.reason or "quarantined"
                                                       if e.quarantined else "")
            case HoldChange() if e.component in self._comp:
                self._comp[e.component].held = e.held
            case JournalHealth():
                self.journal = e
            case LoopLag():
                self.lag = e
            case BoardEvent() if e.channel is not None:
                self._last_event[e.channel] = e.event
            case _:
                return False
        return True

    @property
    def diagnoses(self) -> tuple[tuple[str, ...], ...]:
        return self.diagnosis.diagnoses if self.diagnosis is not None else ()

    @property
    def input_v(self) -> float | None:
        """The board's input voltage (V) while the link is up and the board says it."""
        mv = self.channels.input_mv if self.channels is not None else None
        return mv / 1000.0 if mv is not None and self.link_up else None

    @property
    def currents_a(self) -> list[float]:
        """Every channel's current (A), in channel order; empty before the first sample."""
        return [c.current_ma / 1000.0 for c in self.channels.channels] if self.channels else []

    def statuses(self) -> list[Status]:
        return [*(self._component(c) for c in self.components), *self._board(),
                self._diagnosis(), self._repair(), self._daemon()]

    def _diagnosis(self) -> Status:
        name = f"{PREFIX}/diagnosis"
        if self.diagnosis is None:
            return Status(STALE, name, "not diagnosed yet", PREFIX)
        diags = self.diagnoses
        best = diags[0] if diags else ()
        values = (("best", ", ".join(best) or "none"), ("diagnoses", str(len(diags))),
                  ("all", "; ".join("{" + ", ".join(d) + "}" for d in diags)),
                  ("unknown", ", ".join(self.diagnosis.unknown)))
        if not best and self.diagnosis.unknown:  # unobserved is not healthy
            return Status(STALE, name, "unknown: " + ", ".join(self.diagnosis.unknown), PREFIX,
                          values)
        if not best:
            return Status(OK, name, "every component normal", PREFIX, values)
        return Status(ERROR, name, "best diagnosis {" + ", ".join(best) + "}", PREFIX, values)

    def _repair(self) -> Status:
        name = f"{PREFIX}/repair"
        a = self.last_action
        if a is None:
            return Status(OK, name, "no repair yet", PREFIX, (("action", "none"), ("state", "")))
        text = f"{a.action}({', '.join(a.args)})"
        return Status(ERROR if a.state in BAD_ACTION_STATES else OK, name, f"{text} {a.state}",
                      PREFIX, (("action", text), ("state", str(a.state))))

    def _daemon(self) -> Status:
        j, lag = self.journal, self.lag
        level = ERROR if j.problem else WARN if lag.behind else OK
        message = "; ".join([journal_health_text(j)] + ([loop_lag_text(lag)] if lag.behind
                                                         else []))
        return Status(level, f"{PREFIX}/daemon", message,
                      "daemon", (("journal", j.problem or "writing"),
                                 ("journal_held", str(j.held)),
                                 ("journal_dropped", str(j.dropped)),
                                 ("behind", "true" if lag.behind else "false"),
                                 ("loop_lag_s", f"{lag.lag_s:.3f}")))

    def _component(self, name: str) -> Status:
        comp = self._comp[name]
        diags = self.diagnoses
        inside = sum(1 for d in diags if name in d)
        if self.diagnosis is None:
            level, message = STALE, "not diagnosed yet"
        elif diags and name in diags[0]:
            level, message = ERROR, "abnormal in the best diagnosis {" + ", ".join(diags[0]) + "}"
        elif inside:
            level, message = WARN, f"abnormal in {inside} of {len(diags)} minimal diagnoses"
        elif name in self.diagnosis.unknown:
            level, message = STALE, "unknown: its observations expired"
        else:
            level, message = OK, "normal in every minimal diagnosis"
        if comp.quarantined:
            level, message = ERROR, f"{message}; quarantined: {comp.quarantined}"
        return Status(level, f"{PREFIX}/components/{name}", message, name, (
            ("diagnoses", f"{inside} of {len(diags)}"), ("repair", comp.repair),
            ("quarantined", "true" if comp.quarantined else "false"),
            ("held", "true" if comp.held else "false")))

    def _board(self) -> list[Status]:
        out = [Status(OK if self.link_up else ERROR, f"{PREFIX}/board/link",
                      "link up" if self.link_up else f"link down: {self.link_reason}", "board",
                      (("link", "up" if self.link_up else "down"),
                       ("total_current_a", f"{sum(self.currents_a):.3f}"),
                       ("input_v", "unknown" if self.input_v is None
                        else f"{self.input_v:.3f}")))]
        for c in self.channels.channels if self.channels else ():
            if not self.link_up:
                level, message = STALE, "board link down"
            elif c.state in BAD_STATES:
                level, message = ERROR, c.state
            else:
                level, message = OK, c.state
            out.append(Status(level, f"{PREFIX}/board/channels/{c.name}", message,
                              f"channel {c.id}", (
                ("channel", str(c.id)), ("state", c.state), ("on", str(c.on).lower()),
                ("current_a", f"{c.current_ma / 1000.0:.3f}"),
                ("last_event", self._last_event.get(c.id, "none")))))
        return out
