"""Observers and diagnosis on a clock the caller drives: the same for a live recording and a replay.

``ClockedObservers(observers, sink)`` runs topic observers without timers of their own: the
caller says how far time has come (``advance(t)``) and feeds messages (``feed(msg)``, which
first advances to the message's time). Every observer deadline up to ``t`` fires *at its
deadline* (not when a timer happened to run), earliest first, so the same messages give the
same updates however fast or slow they are driven: as fast as a bag can be read in
``dxboard replay``, or on the wall clock in ``dxboard record``.

``Diagnosing(theory, emit)`` is the daemon's observation set and diagnoser without its loop:
``apply(updates, now)`` folds the updates into the set (``S ⊕ o``), emits each change as an
``Observation`` event and, when the literals changed, diagnoses at once (no debounce, no time
budget: every change gets its diagnosis, so a replay is deterministic) and emits a
``DiagnosisRecord`` when the bad sets differ from the last ones. The diagnoses are ranked as
the diagnoser ranks them (cardinality, then probability) and ties by name, so that two runs
(whose solvers may find tied diagnoses in any order) journal the same list.

``bag_observers`` picks what a bag can feed: the topic observers of the robot's ``observers:``
section, its hardware observer (fed the board's items from ``/board_stream``, which a
``dxboard run`` on ROS 2 publishes: ``host.ros.boardstream``, each at its own stamp; it calls
the link lost only at its cap, ``link_timeout + link_slack``, since a shorter gap in the stream
may be the daemon's own scheduling, which the daemon excuses and a bag cannot tell) and node
presence from the graph (fed the graph samples the recorder wrote on ``/dxboard/graph``:
``host.ros.graphlog``), without process observers (the supervisor is not in a bag). Its
``topics`` are the bag's names (``/dxboard/graph`` for the graph).
"""

from __future__ import annotations

import heapq
import logging
import time
from collections.abc import Callable, Iterator, Sequence
from typing import Any

from host.diagnosis import Diagnoser
from host.diagnosis.coverage import Coverage
from host.diagnosis.logic import Theory
from host.diagnosis.observations import ObservationSet
from host.diagnosis.runner import fold_updates
from host.events import DiagnosisRecord, Event, Observation
from host.observers.base import Observer, Update
from host.observers.hardware import HardwareObserver
from host.observers.sources.ros2_graph import GRAPH
from host.observers.sources.ros2_message import RosMessage
from host.observers.topics import TopicObserver
from host.ros import boardstream, graphlog

log = logging.getLogger(__name__)

Sink = Callable[[list[Update], float], None]
MIN_STEP_S = 0.001  # a deadline that does not move after its tick is retried this much later


def bag_observers(observers: Sequence[Observer[Any]]) -> list[Observer[Any]]:
    """The observers a bag can feed: topic observers (of the graph too), the hardware one
    judging the link at its cap (``stream_link``)."""
    return [stream_link(o) if isinstance(o, HardwareObserver) else o
            for o in observers if isinstance(o, (TopicObserver, HardwareObserver))]


def stream_link(o: HardwareObserver) -> HardwareObserver:
    """A hardware observer like ``o`` that calls the link lost only at ``o``'s cap
    (``link_timeout + link_slack``, 1 s by default): a bag sees the board through the daemon's
    ``/board_stream``, and a shorter gap in it may be the daemon's loop held up, which the
    daemon's own observer excuses and a recorder cannot tell. The daemon's ``LinkDown`` items
    still count at once."""
    return HardwareObserver(o.devices, o.link_timeout + o.link_slack, o.settle, o.link_atom,
                            link_slack=0.0, name=o.name, validity=o.validity,
                            refresh=o.refresh)


class ClockedObservers:
    def __init__(self, observers: Sequence[Observer[Any]], sink: Sink) -> None:
        self.observers = list(observers)
        self.sink = sink
        self.now: float | None = None
        self._by_topic: dict[str, list[TopicObserver]] = {}
        self._hardware = [o for o in self.observers if isinstance(o, HardwareObserver)]
        for o in self.observers:
            if isinstance(o, TopicObserver):
                for t in o.topics:  # the graph's samples are on a topic of their own in a bag
                    self._by_topic.setdefault(graphlog.TOPIC if t == GRAPH else t,
                                              []).append(o)
        if self._hardware:
            self._by_topic.setdefault(boardstream.TOPIC, [])
        self._fired: dict[int, float] = {}

    @property
    def topics(self) -> list[str]:
        return sorted(self._by_topic)

    def start(self, t: float) -> None:
        """Time starts at ``t``: every observer's first tick."""
        self.now = t
        for o in self.observers:
            self._out(o.tick(t), t)

    def next_deadline(self) -> float | None:
        """The earliest deadline of any observer (None: only messages can change anything)."""
        times = [self._due(o) for o in self.observers]
        return min((t for t in times if t is not None), default=None)

    def advance(self, t: float) -> None:
        """Fire every deadline up to ``t``, each at its own time, earliest first."""
        while True:
            due = self.next_deadline()
            if due is None or due > t:
                break
            for o in self.observers:
                if self._due(o) == due:
                    self._fired[id(o)] = due
                    self._out(o.tick(due), due)
        self.now = t if self.now is None else max(self.now, t)

    def feed(self, msg: RosMessage) -> None:
        """One message, at its own time (``boardstream.when``: deadlines before it fire
        first); a ``/board_stream`` item goes to the hardware observer."""
        t = boardstream.when(msg)
        self.advance(t)
        t = max(t, self.now if self.now is not None else t)  # later than its grace: now
        fed = graphlog.from_bag(msg) if msg.topic == graphlog.TOPIC else msg
        if fed is not None:
            for o in self._by_topic.get(msg.topic, ()):
                self._out(o.feed(fed, t), t)
        if msg.topic == boardstream.TOPIC and self._hardware:
            item = boardstream.decode(msg)
            if item is not None:
                for h in self._hardware:
                    self._out(h.feed(item, t), t)

    def stop(self) -> None:
        """Retract what every observer asserted (the recording or the replay ends)."""
        t = self.now if self.now is not None else 0.0
        for o in self.observers:
            self._out(o.stop(t), t)

    def _due(self, o: Observer[Any]) -> float | None:
        deadline = o.next_deadline()
        fired = self._fired.get(id(o))
        if deadline is not None and fired is not None and deadline <= fired:
            return fired + MIN_STEP_S  # never spin on a deadline that did not move
        return deadline

    def _out(self, updates: list[Update], t: float) -> None:
        if updates:
            self.sink(updates, t)


class Reorder:
    """Messages in the order of their own times (``boardstream.when``: a board item's stamp
    comes a little before its arrival), each released once the clock is ``grace`` seconds
    past it; ties keep the order they came in. Live (the clock) and in a replay (the arrival
    times of the bag) the same messages come out in the same order."""

    def __init__(self, grace: float) -> None:
        self.grace = grace
        self._heap: list[tuple[float, int, RosMessage]] = []
        self._seq = 0

    def push(self, msg: RosMessage) -> None:
        self._seq += 1
        heapq.heappush(self._heap, (boardstream.when(msg), self._seq, msg))

    def first(self) -> float | None:
        """When the next message is due (its time plus the grace)."""
        return self._heap[0][0] + self.grace if self._heap else None

    def due(self, now: float) -> Iterator[RosMessage]:
        """The messages whose time is ``grace`` seconds past at ``now``, in order."""
        while self._heap and self._heap[0][0] + self.grace <= now:
            yield heapq.heappop(self._heap)[2]

    def drain(self) -> Iterator[RosMessage]:
        """Every message left, in order."""
        while self._heap:
            yield heapq.heappop(self._heap)[2]


class Diagnosing:
    def __init__(self, theory: Theory, emit: Callable[[Event], None],
                 max_card: int | None = None, max_count: int | None = 20) -> None:
        self.emit = emit
        self.observations = ObservationSet()
        self.known = theory.observable_atoms()
        self.diagnoser = Diagnoser(theory, observations=self.observations)
        self.bounds = {"max_card": max_card, "max_count": max_count}
        self.records: list[DiagnosisRecord] = []
        self.coverage = Coverage(theory)  # what expired is unknown, not healthy
        self._last: tuple[list[frozenset[str]], tuple[str, ...]] | None = None

    def apply(self, updates: list[Update], now: float) -> None:
        if fold_updates(updates, self.observations, self.known, self.emit):
            self.diagnose(now, "observation")

    def diagnose(self, now: float, trigger: str) -> None:
        for gone in self.observations.expire(now):
            self.emit(Observation(gone.literal.atom, None, "expired"))
        t0 = time.perf_counter()
        literals = self.observations.literals()
        unknown = self.coverage.observe({lit.atom for lit in literals})
        result = self.diagnoser.diagnose(literals=literals,
                                         **self.bounds)  # type: ignore[arg-type]
        ranked = sorted(result.diagnoses, key=lambda d: (
            len(d.bad), -round(d.probability, 9), sorted(d.bad)))
        bad = [d.bad for d in ranked]
        if (bad, unknown) != self._last:
            self._last = (bad, unknown)
            record = DiagnosisRecord.of(
                bad, complete=result.complete, trigger=trigger,
                elapsed_s=time.perf_counter() - t0,
                probabilities=[d.probability for d in ranked], unknown=unknown)
            self.records.append(record)
            self.emit(record)

    def close(self) -> None:
        self.diagnoser.close()
