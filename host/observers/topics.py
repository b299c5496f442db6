"""Topic observers: a topic's frequency (general observer) and input→output responses (multiple).

``FrequencyObserver`` is paper 000's general observer GObs: ``ok(t)`` iff the frequency
``f`` of topic ``t`` measured over a window ``ω`` satisfies ``|f - mu| < sigma`` (``rate`` mu,
``tolerance`` sigma, Hz). ``f`` is estimated from the messages inside the window as
(n - 1) / (t_last - t_first), which is unbiased before the window has filled. Silence is
judged on its own: once no message came for ``silence`` periods (``silence / mu`` seconds),
``¬ok(t)`` is emitted at that deadline.

``ResponseObserver`` is the multiple observer MObs: after a message on ``input``, a message on
``output`` must follow within ``within`` seconds; it emits ``ok(output)`` when one does and
``¬ok(output)`` at the deadline when none did (only the oldest unanswered input counts).

Detection latency (from the fault to the literal, plus the hub's scheduling delay):

- topic silent: ``silence / mu`` after the last message (5 periods by default: 50 ms at 100 Hz,
  0.5 s at 10 Hz; the original engine needed 2 s);
- rate wrong but not zero: one message interval once the window holds only the new regime,
  at most ``ω`` plus an interval;
- response missing: exactly ``within`` after the unanswered input; a response: at once.
"""

from __future__ import annotations

from collections import deque

import host.atoms as A
from host.observers.base import DEFAULT_REFRESH, DEFAULT_VALIDITY, Observer
from host.observers.payload import Message

DEFAULT_SILENCE = 5.0  # periods without a message before a topic counts as silent


class TopicObserver(Observer[Message]):
    """An observer fed with the messages of ``topics``."""

    topics: tuple[str, ...] = ()


class FrequencyObserver(TopicObserver):
    kind = "frequency"
    needs_input = False

    def __init__(self, topic: str, rate: float, tolerance: float, window: float = 1.0,
                 silence: float = DEFAULT_SILENCE, atom: str | None = None, *,
                 name: str | None = None, validity: float = DEFAULT_VALIDITY,
                 refresh: float = DEFAULT_REFRESH) -> None:
        super().__init__(name or f"frequency:{topic}", validity, refresh)
        if rate <= 0 or tolerance <= 0 or window * rate < 2 or silence <= 0:
            raise ValueError(f"{self.name}: need rate > 0, tolerance > 0, silence > 0 and "
                             "a window holding at least 2 messages (window * rate >= 2)")
        self.topics = (topic,)
        self.atom = atom or str(A.ok(topic))
        self.rate = rate
        self.tolerance = tolerance
        self.window = window
        self.max_gap = silence / rate
        self._times: deque[float] = deque()
        self._start: float | None = None
        self.frequency: float | None = None  # the last estimate, for journals and tests

    def atoms(self) -> list[str]:
        return [self.atom]

    def _feed(self, item: Message, now: float) -> None:
        if self._start is None:
            self._start = now
        times = self._times
        times.append(now)
        while times[0] + self.window < now:
            times.popleft()
        if len(times) < 2:
            return  # one message says nothing about a rate; silence is judged by _check
        span = times[-1] - times[0]
        self.frequency = (len(times) - 1) / span if span > 0 else float("inf")
        self._say(self.atom, abs(self.frequency - self.rate) < self.tolerance, now)

    def _silent_since(self) -> float | None:
        if self._times:
            return self._times[-1]
        return self._start

    def _check(self, now: float) -> None:
        if self._start is None:
            self._start = now  # the first tick starts the clock for a topic never heard
        since = self._silent_since()
        if since is not None and now >= since + self.max_gap:
            self.frequency = 0.0
            self._say(self.atom, False, now)

    def _deadline(self) -> float | None:
        since = self._silent_since()
        if since is None or self.asserted.get(self.atom) is False:
            return None  # already judged silent (or not started): only a message changes it
        return since + self.max_gap


class ResponseObserver(TopicObserver):
    kind = "response"
    needs_input = False

    def __init__(self, input: str, output: str, within: float, atom: str | None = None, *,
                 name: str | None = None, validity: float = DEFAULT_VALIDITY,
                 refresh: float = DEFAULT_REFRESH) -> None:
        super().__init__(name or f"response:{input}->{output}", validity, refresh)
        if within <= 0 or input == output:
            raise ValueError(f"{self.name}: need within > 0 and two different topics")
        self.topics = (input, output)
        self.input = input
        self.output = output
        self.within = within
        self.atom = atom or str(A.ok(output))
        self._pending: float | None = None  # time of the oldest unanswered input

    def atoms(self) -> list[str]:
        return [self.atom]

    def _feed(self, item: Message, now: float) -> None:
        self._check(now)
        if item.topic == self.input:
            if self._pending is None:
                self._pending = now
        elif item.topic == self.output and self._pending is not None:
            self._pending = None
            self._say(self.atom, True, now)

    def _check(self, now: float) -> None:
        if self._pending is not None and now >= self._pending + self.within:
            self._pending = None
            self._say(self.atom, False, now)

    def _deadline(self) -> float | None:
        return None if self._pending is None else self._pending + self.within
