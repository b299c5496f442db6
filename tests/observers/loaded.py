"""A loaded machine on a simulated clock, for the observers that judge silence.

``Loaded`` plays the hub's part (``host.observers.hub``) on a consumer that stalls now and then,
as a daemon does when the machine is busy: while it is stalled nothing is fed and no timer
fires; when it resumes, the timer that came due fires first (late) and then every input that
queued up meanwhile is fed, all at once, at the time it was finally read — the worst bunching
there is. Inputs sent during a ``delayed`` spell arrive at its end (held up on their way, as by
a descheduled publisher or board process), while the consumer's own timers stay on time.
No wall clock, no timing assertions: the verdicts and their simulated times are the result.
"""

from __future__ import annotations

import random
from collections.abc import Callable, Sequence
from typing import Any

from host.observers.base import Observer, Update

Send = tuple[float, Callable[[float], Any]]  # (time sent, the input as read at a given time)


def stalls(seed: int, end: float, longest: float, shortest: float = 0.2
           ) -> list[tuple[float, float]]:
    """Seeded spells: one every 0.1-0.5 s, each ``shortest``-1.0 times ``longest`` s."""
    rng = random.Random(seed)
    out, t = [], 0.5
    while t < end:
        d = rng.uniform(shortest, 1.0) * longest
        out.append((t, t + d))
        t += d + rng.uniform(0.1, 0.5)
    return out


class Loaded:
    """Feeds and ticks ``obs`` as a hub would, on a consumer stalled during ``stalled``;
    inputs sent during ``delayed`` arrive at its end."""

    def __init__(self, obs: Observer[Any], stalled: list[tuple[float, float]],
                 delayed: Sequence[tuple[float, float]] = ()) -> None:
        self.obs = obs
        self.stalled = stalled
        self.delayed = list(delayed)
        self.updates: list[Update] = []

    def resumed(self, t: float) -> float:
        """When the consumer gets to something due at ``t``."""
        for a, b in self.stalled:
            if a <= t < b:
                return b
        return t

    def arrives(self, sent: float) -> float:
        for a, b in self.delayed:
            if a <= sent < b:
                return self.resumed(b)
        return self.resumed(sent)

    def run(self, sends: Sequence[Send], end: float) -> None:
        """Deliver ``sends`` (in the order sent) and tick until ``end``."""
        i = 0
        while True:
            due = self.obs.next_deadline()
            tick = None if due is None else self.resumed(due)
            arrival = self.arrives(sends[i][0]) if i < len(sends) else None
            if arrival is not None and (tick is None or arrival < tick):
                self.updates += self.obs.feed(sends[i][1](arrival), arrival)
                i += 1
            elif tick is not None and tick <= end:
                self.updates += self.obs.tick(tick)  # a late timer fires before the backlog
            else:
                return

    def verdicts(self, atom: str) -> list[tuple[bool | None, float]]:
        """The changes of ``atom``: (positive, or None when retracted; simulated time)."""
        out: list[tuple[bool | None, float]] = []
        for u in self.updates:
            lit = getattr(u, "literal", None)
            if lit is not None and lit.atom == atom:
                value: bool | None = lit.positive
            elif getattr(u, "atom", None) == atom:
                value = None
            else:
                continue
            if not out or out[-1][0] != value:
                out.append((value, u.time))
        return out
