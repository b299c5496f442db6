"""Value observers: the trend of a value (QObs), two trends matching (BiQObs), and thresholds
on key/value pairs (DObs), all reading values from JSON topic payloads by key.

``TrendObserver`` fits a line (``numpy.polyfit``, degree 1) to the samples of value ``v`` from
the last ``window`` seconds and compares the slope ``s`` with the configured ``slope`` b:
``s > b`` is ``inc(v)``, ``s < -b`` is ``dec(v)``, otherwise ``const(v)``; the other two trend
atoms are emitted negated, so the set always says exactly one trend. With fewer than
``min_samples`` samples in the window the trend is unknown and the three atoms are retracted.

``MatchObserver`` keeps the same estimate for two values (each from its topic and key) and
emits ``matched(v1,v2)`` iff both trends are known and equal (``¬matched`` if they differ).

``DiagnosticObserver`` is the bridge to ROS-style diagnostics: each rule takes the value at a
key of a topic's messages and asserts its literal (e.g. ``ok(temp_cpu1)``) iff the value lies
in ``[min, max]`` (either bound optional) or equals ``equals``; a message without the key
changes nothing. Like ROS diagnostic analyzers, one message can feed several rules.

Detection latency: a trend flips once the regression over the window crosses ±b (a step in
slope shows within about ω/2); a matched flip follows the later of its two trends; a threshold
crossing is reported on the first message that shows it. With no messages for ``validity``
seconds (or too few samples in the window) every literal is retracted: unknown, not false.
"""

from __future__ import annotations

from collections import deque
from collections.abc import Sequence
from dataclasses import dataclass

import host.atoms as A
from host.observers.base import DEFAULT_REFRESH, DEFAULT_VALIDITY
from host.observers.payload import TopicMessage, pick
from host.observers.topics import TopicObserver

TRENDS = A.TRENDS


class Trend:
    """The slope of one value over a sliding window (no clock: times are passed in)."""

    def __init__(self, window: float, slope: float, min_samples: int = 3) -> None:
        if window <= 0 or slope < 0 or min_samples < 2:
            raise ValueError("need window > 0, slope >= 0 and min_samples >= 2")
        self.window = window
        self.slope = slope
        self.min_samples = min_samples
        self._t: deque[float] = deque()
        self._v: deque[float] = deque()
        self.fitted: float | None = None  # the last fitted slope

    def add(self, t: float, v: float) -> None:
        self._t.append(t)
        self._v.append(v)
        self.trim(t)

    def trim(self, now: float) -> None:
        while self._t and self._t[0] + self.window <= now:
            self._t.popleft()
            self._v.popleft()

    def label(self) -> str | None:
        """``inc``, ``dec`` or ``const``; None with too few samples."""
        if len(self._t) < self.min_samples or self._t[-1] == self._t[0]:
            self.fitted = None
            return None
        import numpy as np  # here, not at the top: reading the observers' section needs no numpy

        t = np.fromiter(self._t, float, len(self._t))
        v = np.fromiter(self._v, float, len(self._v))
        self.fitted = float(np.polyfit(t - t[-1], v, 1)[0])
        if self.fitted > self.slope:
            return "inc"
        if self.fitted < -self.slope:
            return "dec"
        return "const"

    def runs_dry_at(self) -> float | None:
        """When the window will hold fewer than ``min_samples`` samples, absent new ones."""
        if len(self._t) < self.min_samples:
            return None
        return self._t[-self.min_samples] + self.window


@dataclass(frozen=True)
class ValueRef:
    """Value ``name`` is the number at ``key`` in the messages of ``topic``."""

    name: str
    topic: str
    key: str


class TrendObserver(TopicObserver):
    kind = "trend"

    def __init__(self, value: ValueRef, window: float = 1.0, slope: float = 0.0,
                 min_samples: int = 3, *, name: str | None = None,
                 validity: float = DEFAULT_VALIDITY, refresh: float = DEFAULT_REFRESH) -> None:
        super().__init__(name or f"trend:{value.name}", validity, refresh)
        self.value = value
        self.topics = (value.topic,)
        self.trend = Trend(window, slope, min_samples)

    def atoms(self) -> list[str]:
        return [str(A.trend(t, self.value.name)) for t in TRENDS]

    def _feed(self, item: TopicMessage, now: float) -> None:
        v = item.number(self.value.key)
        if v is not None:
            self.trend.add(now, v)
            self._judge(now)

    def _judge(self, now: float) -> None:
        label = self.trend.label()
        for t, atom in zip(TRENDS, self.atoms(), strict=True):
            if label is None:
                self._forget(atom, now)
            else:
                self._say(atom, t == label, now)

    def _check(self, now: float) -> None:
        self.trend.trim(now)
        if self._said:
            self._judge(now)

    def _deadline(self) -> float | None:
        return self.trend.runs_dry_at() if self._said else None


class MatchObserver(TopicObserver):
    kind = "match"

    def __init__(self, v1: ValueRef, v2: ValueRef, window: float = 1.0, slope: float = 0.0,
                 min_samples: int = 3, *, name: str | None = None,
                 validity: float = DEFAULT_VALIDITY, refresh: float = DEFAULT_REFRESH) -> None:
        super().__init__(name or f"match:{v1.name},{v2.name}", validity, refresh)
        self.refs = (v1, v2)
        self.topics = tuple(dict.fromkeys((v1.topic, v2.topic)))
        self.trends = (Trend(window, slope, min_samples), Trend(window, slope, min_samples))
        self.atom = str(A.matched(v1.name, v2.name))

    def atoms(self) -> list[str]:
        return [self.atom]

    def _feed(self, item: TopicMessage, now: float) -> None:
        for ref, trend in zip(self.refs, self.trends, strict=True):
            if item.topic == ref.topic:
                v = item.number(ref.key)
                if v is not None:
                    trend.add(now, v)
        self._judge(now)

    def _judge(self, now: float) -> None:
        a, b = (t.label() for t in self.trends)
        if a is None or b is None:
            self._forget(self.atom, now)
        else:
            self._say(self.atom, a == b, now)

    def _check(self, now: float) -> None:
        for t in self.trends:
            t.trim(now)
        if self._said:
            self._judge(now)

    def _deadline(self) -> float | None:
        times = [t.runs_dry_at() for t in self.trends]
        known = [t for t in times if t is not None]
        return min(known) if known and self._said else None


@dataclass(frozen=True)
class Threshold:
    """``atom`` holds iff the value at ``key`` is in ``[min, max]`` (or equals ``equals``)."""

    key: str
    atom: str
    min: float | None = None
    max: float | None = None
    equals: str | float | bool | None = None

    def holds(self, value: object) -> bool | None:
        if self.equals is not None:
            return value == self.equals
        if isinstance(value, bool) or not isinstance(value, int | float):
            return None  # not a number: no judgement
        return ((self.min is None or value >= self.min)
                and (self.max is None or value <= self.max))


class DiagnosticObserver(TopicObserver):
    kind = "diagnostic"

    def __init__(self, topic: str, rules: Sequence[Threshold], *, name: str | None = None,
                 validity: float = DEFAULT_VALIDITY, refresh: float = DEFAULT_REFRESH) -> None:
        super().__init__(name or f"diagnostic:{topic}", validity, refresh)
        if not rules:
            raise ValueError(f"{self.name}: no rules")
        self.topics = (topic,)
        self.rules = tuple(rules)

    def atoms(self) -> list[str]:
        return [r.atom for r in self.rules]

    def _feed(self, item: TopicMessage, now: float) -> None:
        values = item.values
        for rule in self.rules:
            value = pick(values, rule.key)
            ok = None if value is None else rule.holds(value)
            if ok is not None:
                self._say(rule.atom, ok, now)
