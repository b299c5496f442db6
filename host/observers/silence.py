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
- ``OwnTime``: where the publisher's processes are known (``host.observers.starvation``), a gap
  is measured in the publisher chain's *own* time instead: the wall time minus the time its
  most starved thread spent runnable but waiting for a CPU, read from the first moment the
  gap looks long, and confirmed only while none of its threads is stuck on the run queue. A
  hung publisher sleeps, so its own time runs with the wall clock and it is found at its limit
  plus ``JITTER_S``; a starved one waits on the run queue, so its gap is excused while it
  waits — up to a cap (``STARVED_CAP_S`` past the limit), after which it is silence all the
  same.

Pure values, no clock: the observers pass ``now`` in (and ``OwnTime`` the probe's reading).
"""

from __future__ import annotations

from collections import deque
from typing import NamedTuple

JITTER_S = 0.02  # a silence is confirmed this long after it was noticed, by an on-time tick
JITTER_GAIN = 2.0  # the delay tolerated: this times the worst seen lately
JITTER_MEMORY_S = 60.0  # how long a delay seen is remembered (a busy spell)
STARVED_CAP_S = 2.0  # a gap this long past its limit is silence, however starved its publisher
CATCH_UP = 0.5  # own time a starved chain needs to catch up, per second it waited


class ChainState(NamedTuple):
    """A reading of a publisher chain (``host.observers.starvation``): its run-queue wait so
    far (seconds, never decreasing) and how many of its threads are stuck on the run queue
    (runnable at this reading and the previous one, with no CPU in between)."""

    wait: float
    stuck: int


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


class OwnTime:
    """A gap judged in the publisher chain's own time: silence once it reaches ``need``.

    ``silent(now, chain, since, need, cap)`` at each tick, with ``chain`` the probe's reading
    and ``since`` the last message. The first reading (at ``start``) takes the gap until then
    as the chain's own; from there, between two readings, its own time is the wall time minus
    its wait, bounded by the wall time; an interval with a thread stuck on the run queue (its
    wait not yet counted: Linux adds it when the thread gets the CPU) is all starved and
    confirms nothing. A tick more than ``JITTER_S`` after its
    deadline means the daemon's loop was stalled (messages may be queued behind it): whatever
    was counted, a further ``JITTER_S`` of own time is needed. A chain that was starved has
    work to catch up on once it runs again (the frames it missed; the emulator, which plays
    every device, uses up to half a CPU): ``need`` grows by ``CATCH_UP`` times the wait seen.
    At ``cap`` it is silence however
    starved the chain.
    """

    def __init__(self, confirm: float = JITTER_S) -> None:
        self.confirm = confirm
        self.own = 0.0  # the gap in the chain's own time, as counted at the last reading
        self.starved = 0.0  # its run-queue wait since the first reading
        self._at: float | None = None  # the last reading, and the wait then
        self._wait = 0.0
        self._due: float | None = None
        self._since = 0.0
        self.capped = False  # the last silence was called at the cap, the chain starved

    def reset(self) -> None:
        """An input arrived: whatever gap was being counted has ended."""
        self._at = self._due = None
        self.own = self.starved = 0.0

    def silent(self, now: float, chain: ChainState, since: float, need: float,
               cap: float) -> bool:
        """At a tick at ``now``: is the gap since ``since`` a silence?"""
        late = self._due is not None and now > self._due + JITTER_S
        self._since = since
        if self._at is None:
            self.own = now - since
        else:
            dt = now - self._at
            starved = dt if chain.stuck else min(max(0.0, chain.wait - self._wait), dt)
            self.own += dt - starved
            self.starved += starved
        if late:
            self.own = min(self.own, self._need(need) - self.confirm)
        self._at, self._wait = now, chain.wait
        confirmed = self.own >= self._need(need) - 1e-9 and not chain.stuck
        self.capped = now >= cap and not confirmed
        return confirmed or now >= cap

    def _need(self, need: float) -> float:
        return need + CATCH_UP * self.starved

    def deadline(self, start: float, need: float, cap: float) -> float:
        """When the next tick is due: the first reading, or the earliest the own time could
        reach ``need`` — at least ``confirm / 4`` on, and once the gap is past ``need`` in wall
        time a quarter of the excess (a few dozen readings of /proc in a starved gap up to the
        cap, not one every few milliseconds)."""
        if self._at is None:
            due = start
        else:
            need = self._need(need)
            excess = self._at - self._since - need
            step = max(need - self.own, self.confirm / 4, excess / 4)
            due = min(cap, self._at + step)
        self._due = due
        return due
