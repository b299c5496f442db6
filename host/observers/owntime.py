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
earlier: what is counted may include that much before the window), plus, when a thread of the
chain is stuck on the run queue now, the time since the previous reading (Linux adds a wait
when the thread gets the CPU), at most the window's span.

The same publisher, once it runs again, publishes its backlog: the window that starts after its
wait holds more messages than its span had room for, a rate too *high*. A high rate is judged
again over the span plus what the chain waited in the window before it (``WindowWait.before``,
from the readings).

A publisher that really slowed down sleeps between its messages rather than waiting for a
CPU: its own time is the wall time and the low rate is said at once. Pure values, no clock.
"""

from __future__ import annotations

from collections import deque

from host.observers.silence import ChainState

READS = 2  # probe readings per window while messages come (each reads /proc for the chain)


class WindowWait:
    """The publisher chain's run-queue wait within the last ``window`` seconds (readings
    ``add``ed as messages come, ``READS`` a window; see the module docstring)."""

    def __init__(self, window: float) -> None:
        self.every = window / READS
        self.memory = 2 * window + self.every  # a window and the one before it
        self._readings: deque[tuple[float, float]] = deque()  # (time, the chain's wait)

    def due(self, now: float) -> bool:
        """Is a reading due at ``now``?"""
        r = self._readings
        return not r or now - r[-1][0] >= self.every

    def add(self, now: float, chain: ChainState) -> None:
        r = self._readings
        if r and (now < r[-1][0] or chain.wait < r[-1][1]):
            r.clear()  # another probe, or time went back: start afresh
        r.append((now, chain.wait))
        while len(r) > 1 and r[1][0] <= now - self.memory:
            r.popleft()

    def _at(self, t: float) -> float:
        """The chain's wait at the last reading at or before ``t`` (the earliest there is)."""
        r = self._readings
        base = r[0][1]
        for at, wait in r:
            if at > t:
                break
            base = wait
        return base

    def before(self, start: float, end: float) -> float:
        """The chain's wait between ``start`` and ``end`` (past times) from the readings: from
        the last reading at or before each."""
        if not self._readings:
            return 0.0
        return max(0.0, min(self._at(end) - self._at(start), end - start))

    def within(self, start: float, now: float, chain: ChainState) -> float:
        """The chain's wait between ``start`` and ``now`` with ``chain`` read at ``now``: since
        the last reading at or before ``start`` (the earliest there is: less may be counted),
        at most ``now - start``."""
        self.add(now, chain)
        r = self._readings
        waited = chain.wait - self._at(start)
        if chain.stuck and len(r) > 1:
            waited += now - r[-2][0]  # stuck on the run queue since then, not yet counted
        return max(0.0, min(waited, now - start))
