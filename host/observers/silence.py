"""Judging silence on a busy machine: the delay seen lately, and a gap confirmed by an awake loop.

Two observers decide that something fell silent: the frequency observer (a topic without
messages, ``host.observers.topics``) and the hardware observer (a board without readings, its
link rule in ``host.observers.hardware``). On a loaded machine both see gaps that are no
silence — a descheduled publisher or board process, a daemon loop held up while messages queue
behind it — and both tolerate them the same way:

- ``SlidingExtreme`` remembers the worst delay seen in the last ``memory`` seconds (a busy
  spell); the silence limit grows with it, capped by the observer's own bound;
- ``Confirmation``: once a gap reaches its limit it is *noticed* by a tick, and *confirmed*
  by a tick ``JITTER_S`` later that comes on time (at most ``JITTER_S`` late). A late tick
  means the loop itself was stalled — inputs may be queued behind it, not yet fed — so the
  confirmation starts again. However stalled the loop, a gap that reaches the ``hard`` bound
  is silence at once: a silent source is found within its bound.

Pure values, no clock: the observers pass ``now`` in.
"""

from __future__ import annotations

from collections import deque

JITTER_S = 0.02  # a silence is confirmed this long after it was noticed, by an on-time tick
JITTER_GAIN = 2.0  # the delay tolerated: this times the worst seen lately
JITTER_MEMORY_S = 60.0  # how long a delay seen is remembered (a busy spell)


class SlidingExtreme:
    """The least (or greatest) value pushed within the last ``memory`` seconds."""

    def __init__(self, memory: float, greatest: bool) -> None:
        self.memory = memory
        self.sign = -1.0 if greatest else 1.0
        self._q: deque[tuple[float, float]] = deque()  # (time, sign * value), increasing

    def push(self, t: float, value: float) -> None:
        v = self.sign * value
        q = self._q
        while q and q[-1][1] >= v:
            q.pop()
        q.append((t, v))
        while q[0][0] < t - self.memory:
            q.popleft()

    def get(self, now: float | None = None) -> float | None:
        """The extreme; with ``now``, of the last ``memory`` seconds before it (values pushed
        seldom — only those that matter — expire here rather than at the next push)."""
        q = self._q
        if now is not None:
            while q and q[0][0] < now - self.memory:
                q.popleft()
        return None if not q else self.sign * q[0][1]

    def clear(self) -> None:
        self._q.clear()


class Confirmation:
    """A gap noticed at its limit and confirmed by an on-time tick (see the module docstring)."""

    def __init__(self) -> None:
        self.noticed: float | None = None  # an on-time tick saw the gap reach its limit here

    def reset(self) -> None:
        """An input arrived: whatever gap was noticed has ended."""
        self.noticed = None

    def silent(self, now: float, limit: float, hard: float) -> bool:
        """At a tick at ``now``: is the gap that reached ``limit`` (or ``hard``) a silence?"""
        if now >= hard:
            self.noticed = None
            return True  # however stalled the loop
        if now < limit:
            return False
        if self.noticed is None:
            self.noticed = now  # long enough: confirm it a little later
        elif now >= self.noticed + JITTER_S:
            if now <= self.noticed + 2 * JITTER_S:
                self.noticed = None
                return True  # the loop was awake all through: nothing is queued
            self.noticed = now  # the loop stalled meanwhile: confirm again
        return False

    def deadline(self, limit: float) -> float:
        """When the next tick is due for a gap judged against ``limit``."""
        return limit if self.noticed is None else self.noticed + JITTER_S
