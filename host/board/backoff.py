"""The one reconnect policy of the board link: exponential backoff with jitter and a cap.

Whoever reconnects to a board waits ``Backoff.next()`` seconds before each attempt: the board
client's link after a lost link (``host.board.link``) and the daemon between two clients
(``host.daemon.core``). The nominal wait starts at ``first_s`` and doubles after every attempt
up to ``cap_s``; each wait is drawn uniformly from [``1 - jitter``, 1] of it (half by default),
so that many hosts that lost one board (or a board that lost many hosts) do not come back in
step. ``reset()`` after a good connection starts again from ``first_s``. ``attempts`` counts the
waits handed out since the last reset (0: the first failure since the link was good, which a
caller may report once). The random numbers come from the ``rng`` passed in, so a test can fix
them; the policy never sleeps and reads no clock itself.
"""

from __future__ import annotations

import random

FIRST_S = 0.1  # the first nominal wait after a good connection
CAP_S = 5.0  # the nominal wait never grows beyond this
JITTER = 0.5  # each wait is drawn from [1 - JITTER, 1] of the nominal one


class Backoff:
    """Jittered exponential backoff with a cap; see the module docstring."""

    def __init__(self, first_s: float = FIRST_S, cap_s: float = CAP_S, *,
                 jitter: float = JITTER, rng: random.Random | None = None) -> None:
        if not 0 < first_s <= cap_s:
            raise ValueError(f"backoff: need 0 < first_s ({first_s}) <= cap_s ({cap_s})")
        if not 0 <= jitter <= 1:
            raise ValueError(f"backoff: jitter {jitter} is not within 0..1")
        self.first_s = first_s
        self.cap_s = cap_s
        self.jitter = jitter
        self.rng = rng or random.Random()
        self.attempts = 0
        self._nominal = first_s

    @property
    def nominal_s(self) -> float:
        """The nominal wait the next ``next()`` draws from (before jitter)."""
        return self._nominal

    def next(self) -> float:
        """The wait before the next attempt (seconds); the nominal wait doubles, up to the cap."""
        wait = self._nominal * (1.0 - self.jitter + self.jitter * self.rng.random())
        self._nominal = min(self._nominal * 2, self.cap_s)
        self.attempts += 1
        return wait

    def reset(self) -> None:
        """A good connection: the next failure waits from ``first_s`` again."""
        self._nominal = self.first_s
        self.attempts = 0
