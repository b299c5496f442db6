"""A topic's rate learned from its arrival times: ROS 2 topic statistics, and the observer it backs.

``period_windows(times, window)`` cuts the arrivals into consecutive windows of ``window``
seconds and gives, per window, the ``message_period`` statistics that ROS 2 topic statistics
publish (``rclcpp::topic_statistics``: the periods between consecutive arrivals that end in the
window, their mean, standard deviation and maximum, and how many there were). ``learn_rate``
folds them into a ``RateEvidence``: the mean rate over the whole recording, the spread of the
per-window rates, the largest gap, and whether the topic is *periodic* (the periods' coefficient
of variation below ``PERIODIC_CV``: a timer or a device's frame clock) or *reactive* (irregular
arrivals: published in answer to events, which a frequency observer would misjudge). For a
periodic topic ``propose`` gives the general observer's ``rate``, ``tolerance``, ``window`` and
``silence`` (``host.observers.config``) that the evidence supports: a window holding about
``MESSAGES_PER_WINDOW`` messages, a tolerance wide enough for the measured spread and for the
count's quantisation in that window but below the rate (so that a silent topic is never ok),
and a silence (in periods) above the largest gap seen. Pure functions over numbers: the live
watcher, the bag reader and the tests feed them alike.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Sequence
from dataclasses import dataclass

PERIODIC_CV = 0.5  # periods' stddev / mean below this: periodic
MIN_SAMPLES = 5  # fewer arrivals than this back no rate at all
MESSAGES_PER_WINDOW = 10  # the proposed window holds about this many messages
MIN_WINDOW_S = 0.5
SPREAD_FACTOR = 4.0  # tolerance >= this many standard deviations of the per-window rate
MAX_TOLERANCE = 0.75  # tolerance < this share of the rate: a silent topic is never ok
MIN_SILENCE = 4.0  # periods (the observers' default)
GAP_MARGIN = 1.5  # silence >= this times the largest gap seen (in periods)


@dataclass(frozen=True)
class PeriodWindow:
    """``message_period`` statistics of one window (seconds), as ROS 2 topic statistics."""

    start: float
    count: int  # periods ending in the window
    mean: float
    stddev: float
    max: float


@dataclass(frozen=True)
class RateEvidence:
    """What a topic's arrivals say: ``n`` messages over ``span`` s, mean ``rate`` (Hz), the
    per-window rates' spread (Hz, stddev), the periods' coefficient of variation and largest
    period (s), and how many windows back it."""

    n: int
    span: float
    rate: float
    spread: float
    cv: float
    max_period: float
    windows: int

    @property
    def periodic(self) -> bool:
        return self.n >= MIN_SAMPLES and self.cv < PERIODIC_CV


@dataclass(frozen=True)
class RateProposal:
    """The general observer's parameters for a periodic topic (``observers: topics:``)."""

    rate: float
    tolerance: float
    window: float
    silence: float


def _mean_std(xs: Sequence[float]) -> tuple[float, float]:
    m = sum(xs) / len(xs)
    return m, math.sqrt(sum((x - m) ** 2 for x in xs) / len(xs))


def period_windows(times: Sequence[float], window: float) -> list[PeriodWindow]:
    """Per window of ``window`` s from the first arrival: the periods that end in it."""
    ts = sorted(times)
    out: list[PeriodWindow] = []
    if len(ts) < 2 or window <= 0:
        return out
    start, periods = ts[0], list[float]()
    for a, b in itertools.pairwise(ts):
        while b >= start + window:
            if periods:
                m, s = _mean_std(periods)
                out.append(PeriodWindow(start, len(periods), m, s, max(periods)))
            start, periods = start + window, []
        periods.append(b - a)
    if periods:
        m, s = _mean_std(periods)
        out.append(PeriodWindow(start, len(periods), m, s, max(periods)))
    return out


def learn_rate(times: Sequence[float], window: float | None = None) -> RateEvidence | None:
    """The rate evidence of these arrival times (None: fewer than ``MIN_SAMPLES``). The
    per-window spread is measured in the window ``propose`` would pick unless one is given."""
    ts = sorted(times)
    if len(ts) < MIN_SAMPLES or ts[-1] <= ts[0]:
        return None
    span = ts[-1] - ts[0]
    rate = (len(ts) - 1) / span
    periods = [b - a for a, b in itertools.pairwise(ts)]
    mean_p, std_p = _mean_std(periods)
    w = window if window is not None else choose_window(rate)
    rates = [c.count / w for c in period_windows(ts, w)[:-1]] or [rate]  # the last is partial
    _, spread = _mean_std(rates)
    return RateEvidence(len(ts), span, rate, spread, std_p / mean_p if mean_p > 0 else 0.0,
                        max(periods), len(rates))


def choose_window(rate: float) -> float:
    """A window holding about ``MESSAGES_PER_WINDOW`` messages at ``rate``, at least 0.5 s."""
    return _round(max(MIN_WINDOW_S, MESSAGES_PER_WINDOW / rate))


def _round(x: float, digits: int = 2) -> float:
    """``x`` to ``digits`` significant digits (a reviewer reads 19.8, not 19.79832)."""
    if x == 0:
        return 0.0
    return round(x, digits - 1 - math.floor(math.log10(abs(x))))


def propose(ev: RateEvidence) -> RateProposal | None:
    """The observer the evidence backs; None for a reactive topic or too few samples."""
    if not ev.periodic:
        return None
    window = choose_window(ev.rate)
    quantum = 2.0 / window  # a count in a window is off by one at either end
    tolerance = max(SPREAD_FACTOR * ev.spread, quantum, 0.25 * ev.rate)
    tolerance = min(tolerance, MAX_TOLERANCE * ev.rate)
    gap = ev.max_period * ev.rate  # the largest gap in periods
    silence = max(MIN_SILENCE, math.ceil(GAP_MARGIN * gap))
    rate = _round(ev.rate)
    window = max(window, _round(2.0 / rate + 0.005))  # the loader wants >= 2 messages a window
    return RateProposal(rate, _round(tolerance), window, float(silence))
