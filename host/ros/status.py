"""The daemon's state in ``diagnostic_msgs`` terms: a projection of the one fold of its events.

``Diagnostics(components, fold)`` reads an ``EventFold`` (``host.fold``: the daemon's event
stream folded once, for the page and for this alike) into what a ROS 2 robot monitor shows; it
folds nothing itself and is pure (no rclpy, no clock), so it is tested on its own and the
publisher (``host.ros.publisher``) only turns its ``DiagnosticStatus`` values into messages.
Status names are paths under ``dxboard/`` that the standard ``diagnostic_aggregator`` groups
into one tree (``ros/dxboard_ros/config/analyzers.yaml``; rqt_robot_monitor shows it as it
is)::

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
behind, loop_lag_s). The fold's ``diagnoses``, ``currents_a`` and ``input_v`` are the latest minimal
diagnoses, channel currents and the board's input voltage, for ``/diagnosis``,
``/board_measurements`` and ``/battery_state``.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass

from host.events import journal_health_text, loop_lag_text
from host.fold import EventFold

OK, WARN, ERROR, STALE = 0, 1, 2, 3
BAD_STATES = ("tripped", "latched", "faulted")
PREFIX = "dxboard"  # the root of every status name: one tree in the aggregator
BAD_ACTION_STATES = ("failed", "timeout")


@dataclass(frozen=True)
class DiagnosticStatus:
    """A REP-107 ``diagnostic_msgs/DiagnosticStatus``, as plain values."""

    level: int
    name: str
    message: str
    hardware_id: str
    values: tuple[tuple[str, str], ...] = ()


class Diagnostics:
    """``/diagnostics`` of ``fold`` for the model's ``components``; it only reads the fold."""

    def __init__(self, components: Sequence[str], fold: EventFold) -> None:
        self.components = list(components)
        self.fold = fold
        self._parts: dict[str, tuple[tuple[int, ...], list[DiagnosticStatus]]] = {}

    def statuses(self) -> list[DiagnosticStatus]:
        return [*self._part("components", ("diagnosis", "excluded", "actions"),
                            self._components),
                *self._part("board", ("channels", "link", "board_events"), self._board),
                self._diagnosis(), self._repair(), self._daemon()]

    def _part(self, name: str, sections: tuple[str, ...],
              make: Callable[[], list[DiagnosticStatus]]) -> list[DiagnosticStatus]:
        """``make()``, again only when one of the fold's ``sections`` it reads changed."""
        seen = tuple(self.fold.sections[s] for s in sections)
        hit = self._parts.get(name)
        if hit is None or hit[0] != seen:
            hit = self._parts[name] = (seen, make())
        return hit[1]

    def _components(self) -> list[DiagnosticStatus]:
        quarantined, held = self.fold.quarantined, self.fold.held
        return [self._component(c, quarantined, held) for c in self.components]

    def _diagnosis(self) -> DiagnosticStatus:
        name = f"{PREFIX}/diagnosis"
        f = self.fold
        if f.diagnosis is None:
            return DiagnosticStatus(STALE, name, "not diagnosed yet", PREFIX)
        diags, best, unknown = f.diagnoses, f.best, f.unknown
        values = (("best", ", ".join(best) or "none"), ("diagnoses", str(len(diags))),
                  ("all", "; ".join("{" + ", ".join(d) + "}" for d in diags)),
                  ("unknown", ", ".join(unknown)))
        if not best and unknown:  # unobserved is not healthy
            return DiagnosticStatus(STALE, name, "unknown: " + ", ".join(unknown), PREFIX,
                                    values)
        if not best:
            return DiagnosticStatus(OK, name, "every component normal", PREFIX, values)
        return DiagnosticStatus(ERROR, name, "best diagnosis {" + ", ".join(best) + "}", PREFIX,
                                values)

    def _repair(self) -> DiagnosticStatus:
        name = f"{PREFIX}/repair"
        a = self.fold.last_action
        if a is None:
            return DiagnosticStatus(OK, name, "no repair yet", PREFIX,
                                    (("action", "none"), ("state", "")))
        text = f"{a.action}({', '.join(a.args)})"
        return DiagnosticStatus(ERROR if a.state in BAD_ACTION_STATES else OK, name,
                                f"{text} {a.state}", PREFIX,
                                (("action", text), ("state", str(a.state))))

    def _daemon(self) -> DiagnosticStatus:
        j, lag = self.fold.journal, self.fold.lag
        level = ERROR if j.problem else WARN if lag.behind else OK
        message = "; ".join([journal_health_text(j)] + ([loop_lag_text(lag)] if lag.behind
                                                         else []))
        return DiagnosticStatus(level, f"{PREFIX}/daemon", message,
                                "daemon", (("journal", j.problem or "writing"),
                                           ("journal_held", str(j.held)),
                                           ("journal_dropped", str(j.dropped)),
                                           ("behind", "true" if lag.behind else "false"),
                                           ("loop_lag_s", f"{lag.lag_s:.3f}")))

    def _component(self, name: str, quarantined_all: dict[str, str],
                   held: dict[str, str]) -> DiagnosticStatus:
        f = self.fold
        diags = f.diagnoses
        inside = sum(1 for d in diags if name in d)
        if f.diagnosis is None:
            level, message = STALE, "not diagnosed yet"
        elif name in f.best:
            level, message = ERROR, "abnormal in the best diagnosis {" + ", ".join(f.best) + "}"
        elif inside:
            level, message = WARN, f"abnormal in {inside} of {len(diags)} minimal diagnoses"
        elif name in f.unknown:
            level, message = STALE, "unknown: its observations expired"
        else:
            level, message = OK, "normal in every minimal diagnosis"
        quarantined = quarantined_all.get(name)
        if quarantined is not None:
            level, message = ERROR, f"{message}; quarantined: {quarantined or 'quarantined'}"
        action = f.action_of.get(name)
        repair = "none" if action is None else \
            f"{action.action}({', '.join(action.args)}) {action.state}"
        return DiagnosticStatus(level, f"{PREFIX}/components/{name}", message, name, (
            ("diagnoses", f"{inside} of {len(diags)}"), ("repair", repair),
            ("quarantined", "true" if quarantined is not None else "false"),
            ("held", "true" if name in held else "false")))

    def _board(self) -> list[DiagnosticStatus]:
        f = self.fold
        volts = f.input_v
        out = [DiagnosticStatus(OK if f.link_up else ERROR, f"{PREFIX}/board/link",
                                "link up" if f.link_up else f"link down: {f.link_reason}",
                                "board",
                                (("link", "up" if f.link_up else "down"),
                                 ("total_current_a", f"{sum(f.currents_a):.3f}"),
                                 ("input_v", "unknown" if volts is None else f"{volts:.3f}")))]
        for c in f.channels.channels if f.channels else ():
            if not f.link_up:
                level, message = STALE, "board link down"
            elif c.state in BAD_STATES:
                level, message = ERROR, c.state
            else:
                level, message = OK, c.state
            out.append(DiagnosticStatus(level, f"{PREFIX}/board/channels/{c.name}", message,
                                        f"channel {c.id}", (
                ("channel", str(c.id)), ("state", c.state), ("on", str(c.on).lower()),
                ("current_a", f"{c.current_ma / 1000.0:.3f}"),
                ("last_event", f.last_board_event.get(c.id, "none")))))
        return out
