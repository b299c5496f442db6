"""The observer hub: routes inputs to observers and runs their deadlines on the asyncio loop.

The daemon's part of the observers, kept small so the daemon only wires: ``ObserverHub``
takes the observers and a ``sink`` (called with every non-empty list of updates, in order —
typically ``lambda u: apply_updates(u, diagnoser)`` followed by a diagnosis); ``start`` subscribes
each topic observer's topics on a ``TopicSource`` and starts a ``ProcessWatcher``; the board
stream is fed with ``feed_board(item)``. After every input the hub (re)arms one timer per
observer at its ``next_deadline()``, so silence, response and link deadlines fire when due and
refreshes go out on time — no fixed poll. A deadline that recedes (a board's link deadline moves
on with each of its hundred readings a second) keeps its timer, which is moved on when it fires:
an observer is ticked only once its deadline is due. The hub reads the clock (``clock``), as the
I/O edge.

A topic observer's rules judge no further than its messages have been read. The source hands
them over through an inbox that a loop far behind drains in slices, its timers running in
between (``emulator.inbox``), so a deadline can fire while messages that came in before it still
wait there, and the observer would call silent a topic whose messages are only queued behind it:
beside CPU hogs, with a stranger flooding ``/odom``, the daemon read its messages up to 4 s after
they came in, called every topic silent at the cap and power-cycled healthy devices (issue 25).
So while a message waits (``TopicSource.waiting_since``) a topic observer is ticked with
``read``, the time the oldest waiting one came in, up to which it has read every message: its
rules judge there (a silence judged there is one), its refreshes go out on time as before. A
deadline that ``read`` has not reached yet is looked at again every ``BEHIND_S`` at most, until
the messages before it are read. A backlog of ``BEHIND_TELL_S`` or more is said on the log. The
board's readings and the processes' samples do not come through the inbox: their observers tick
on the clock.
"""

from __future__ import annotations

import asyncio
import logging
import time
from collections.abc import Callable, Sequence
from typing import Any

from host.observers.base import Observer, Update
from host.observers.hardware import BoardInput, HardwareObserver
from host.observers.payload import TopicMessage
from host.observers.processes import ProcessObserver, ProcessSample
from host.observers.sources.base import Subscription, TopicSource
from host.observers.topics import FrequencyObserver, TopicObserver, WayIn
from host.observers.watcher import ProcessSpec, ProcessWatcher

log = logging.getLogger(__name__)

BEHIND_S = 0.05  # a tick waiting for the inbox looks again this often at most (a drain's slice)
BEHIND_TELL_S = 0.5  # a backlog at least this old is said on the log, once a spell

Sink = Callable[[list[Update]], None]


class ObserverHub:
    def __init__(self, observers: Sequence[Observer[Any]], sink: Sink,
                 clock: Callable[[], float] = time.monotonic) -> None:
        self.observers = list(observers)
        self.sink = sink
        self.clock = clock
        self._by_topic: dict[str, list[TopicObserver]] = {}
        self._by_node: dict[str, list[ProcessObserver]] = {}
        self._hardware: list[HardwareObserver] = []
        for o in self.observers:
            if isinstance(o, TopicObserver):
                for t in o.topics:
                    self._by_topic.setdefault(t, []).append(o)
            elif isinstance(o, ProcessObserver):
                self._by_node.setdefault(o.node, []).append(o)
            elif isinstance(o, HardwareObserver):
                self._hardware.append(o)
        # any topic's latest message: a stalled way in is no silence — where another topic
        # could have come in; with one topic observed, its gap is its own
        self.way_in = WayIn()
        for o in self.observers:
            if isinstance(o, FrequencyObserver) and len(self._by_topic) > 1:
                o.way_in = self.way_in
        self._timers: dict[int, tuple[float, asyncio.TimerHandle]] = {}
        self._subs: list[Subscription] = []
        self._source: TopicSource | None = None
        self._behind_told = False  # this spell of a backlog in the inbox was said
        self.watcher: ProcessWatcher | None = None

    def confirmed(self, atom: str) -> bool:
        """Did the observer that asserts ``atom`` confirm it before saying it
        (``Observer.confirmed``)? What the repair service need not debounce."""
        return any(o.confirmed(atom) for o in self.observers)

    @property
    def topics(self) -> list[str]:
        return list(self._by_topic)

    @property
    def nodes(self) -> list[str]:
        return list(self._by_node)

    async def start(self, source: TopicSource | None = None,
                    processes: dict[str, ProcessSpec] | None = None,
                    poll: float | None = None) -> None:
        """Subscribe the topics, start watching the processes, arm the first deadlines."""
        if source is not None:
            self._source = source
            for topic in self._by_topic:
                self._subs.append(source.subscribe(topic, self.feed_message))
        if processes:
            kw = {} if poll is None else {"poll": poll}
            self.watcher = ProcessWatcher(processes, self.feed_process, clock=self.clock, **kw)
            self.watcher.start()
        now = self.clock()
        for o in self.observers:
            self._deliver(o, o.tick(now))

    async def close(self) -> None:
        """Stop everything; the observers' literals are retracted through the sink."""
        for s in self._subs:
            s.close()
        self._subs.clear()
        if self.watcher is not None:
            await self.watcher.close()
        for _, handle in self._timers.values():
            handle.cancel()
        self._timers.clear()
        now = self.clock()
        for o in self.observers:
            updates = o.stop(now)
            if updates:
                self.sink(updates)

    # -- inputs ----------------------------------------------------------------------------
    def feed_message(self, msg: TopicMessage) -> None:
        self.way_in.arrived(msg.time)
        for o in self._by_topic.get(msg.topic, ()):
            self._deliver(o, o.feed(msg, msg.time))

    def feed_process(self, sample: ProcessSample, now: float) -> None:
        for o in self._by_node.get(sample.node, ()):
            self._deliver(o, o.feed(sample, now))

    def feed_board(self, item: BoardInput, now: float | None = None) -> None:
        t = self.clock() if now is None else now
        for o in self._hardware:
            self._deliver(o, o.feed(item, t))

    # -- deadlines -------------------------------------------------------------------------
    def _deliver(self, o: Observer[Any], updates: list[Update]) -> None:
        if updates:
            self.sink(updates)
        self._arm(o)

    def _arm(self, o: Observer[Any], fired: float | None = None) -> None:
        deadline = o.next_deadline()
        key = id(o)
        old = self._timers.get(key)
        if old is not None:
            if old[0] == deadline or (deadline is not None and old[0] < deadline):
                return  # due then, or earlier: ``_fire`` moves it on (a deadline that only
                # recedes, as a link deadline does with every reading, costs no new timer)
            old[1].cancel()
            del self._timers[key]
        if deadline is None:
            return
        loop = asyncio.get_running_loop()
        delay = max(0.0, deadline - self.clock())
        if deadline == fired:  # a timer that fired a hair early: never spin on it
            delay = max(delay, 0.001)
        self._timers[key] = (deadline, loop.call_later(delay, self._fire, o))

    def _fire(self, o: Observer[Any]) -> None:
        fired = self._timers.pop(id(o), (None, None))[0]
        due = o.next_deadline()
        if due is None or (fired is not None and due > fired):
            self._arm(o)  # the deadline receded meanwhile: no tick before it is due
            return
        now = self.clock()
        read = self._waiting(now) if isinstance(o, TopicObserver) else None
        updates = o.tick(now) if read is None else o.tick(now, read)
        if updates:
            self.sink(updates)
        if read is not None:
            nxt = o.next_deadline()
            if nxt is not None and read <= nxt <= now:  # due, but a message by then is unread
                delay = min(max(nxt - read, 0.001), BEHIND_S)
                self._timers[id(o)] = (nxt, asyncio.get_running_loop().call_later(
                    delay, self._fire, o))
                return
        self._arm(o, fired)

    def _waiting(self, now: float) -> float | None:
        """When the oldest message still waiting in the source's inbox came in (the loop is
        that far behind its messages); None when none that came in before ``now`` waits."""
        waiting = None if self._source is None else self._source.waiting_since()
        if waiting is None or waiting >= now:
            self._behind_told = False
            return None
        if now - waiting < BEHIND_TELL_S:
            self._behind_told = False  # the spell (if any) is over
        elif not self._behind_told:
            self._behind_told = True
            log.warning("the topics' messages are read %.3f s after they came in (the loop is "
                        "behind them): no topic is judged silent ahead of them", now - waiting)
        return waiting
