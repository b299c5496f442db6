"""A topic's rate in its publisher's own time: the window's span less the time it was held up.

A publisher that stamps a message when it publishes it (hector_mapping, a teleop node, most
nodes of a real robot), or a topic judged on arrival times, shows a rate drop wherever its
publisher was held up: descheduled beside a CPU hog, it publishes late and then in a burst, and
until the burst is out the window holds a gap and too few messages. Such a publisher did not
slow down; it waited. The frequency observer (``host.observers.topics``) therefore judges a
*low* rate again in the publisher's own time before saying it, where it knows how long the
publisher was held up within the window.

``WindowWait`` holds the publisher chain's run-queue wait (``host.observers.starvation``'s
``WaitProbe``, the same that excuses silences), read as messages come, ``READS`` times a window,
and once more at the verdict. The wait within the window is the chain's wait since the last
reading at or before the window's start (while messages come, at most half a window
earlier: what is counted may include that much before the window), an interval in which a
thread of the chain was stuck on the run queue counted whole (Linux adds a wait when the
thread gets the CPU), at most the window's span.

The same publisher, once it runs again, publishes its backlog: the window that starts after its
wait holds more messages than its span had room for, a rate too *high*. A high rate is judged
again over the span plus what the chain waited in the window before it (``WindowWait.before``,
from the readings).

A publisher that really slowed down sleeps between its messages rather than waiting for a
CPU: its own time is the wall time and the low rate is said at once. Pure values, no clock.
"""

from __future__ import annotations

from collections import deque
from collections.abc import Callable

from host.observers.silence import ChainState

READS = 2  # probe readings per window while messages come (each reads /proc for the chain)


class WindowWait:
    """The publisher chain's run-queue wait within the last ``window`` seconds (readings
    ``add``ed as messages come, ``READS`` a window; see the module docstring).

    Between two readings the chain was held up for its wait's growth, at most the time
    between them — or all of that time when a thread of it is stuck on the run queue now (its
    wait not yet counted: Linux adds it when the thread gets the CPU), as ``OwnTime`` counts a
    silence's. The readings keep the running total of that."""

    def __init__(self, window: float) -> None:
        self.every = window / READS
        self.memory = 2 * window + self.every  # a window and the one before it
        self._readings: deque[tuple[float, float]] = deque()  # (time, held up so far)
        self._wait = 0.0  # the chain's wait at the last reading
        self._total = 0.0

    def due(self, now: float) -> bool:
        """Is a reading due at ``now``?"""
        r = self._readings
        return not r or now - r[-1][0] >= self.every

    def add(self, now: float, chain: ChainState) -> None:
        r = self._readings
        if r and now >= r[-1][0]:
            dt = now - r[-1][0]
            self._total += dt if chain.stuck else min(max(0.0, chain.wait - self._wait), dt)
        elif r:
            r.clear()  # time went back: start afresh
        self._wait = chain.wait
        if r and now == r[-1][0]:
            r.pop()
        r.append((now, self._total))
        while len(r) > 1 and r[1][0] <= now - self.memory:
            r.popleft()

    def _at(self, t: float) -> float:
        """Held up so far at the last reading at or before ``t`` (the earliest there is)."""
        r = self._readings
        base = r[0][1]
        for at, total in r:
            if at > t:
                break
            base = total
        return base

    def before(self, start: float, end: float) -> float:
        """How long the chain was held up between ``start`` and ``end`` (past times), from
        the readings: from the last reading at or before each."""
        if not self._readings:
            return 0.0
        return max(0.0, min(self._at(end) - self._at(start), end - start))

    def within(self, start: float, now: float, read: Callable[[], ChainState | None]
               ) -> float:
        """How long the chain was held up between ``start`` and ``now``, ``read`` at ``now``
        unless it was already: since the last reading at or before ``start`` (the earliest
        there is: less may be counted), at most ``now - start``; 0 when it cannot be read."""
        r = self._readings
        if not r or r[-1][0] != now:
            chain = read()
            if chain is None:
                return 0.0
            self.add(now, chain)
        return max(0.0, min(self._total - self._at(start), now - start))
