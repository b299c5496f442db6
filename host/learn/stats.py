"""A topic's rate learned from its arrival times: ROS 2 topic statistics, and the observer it backs.

``period_windows(times, window)`` cuts the arrivals into consecutive windows of ``window``
seconds and gives, per window, the ``message_period`` statistics that ROS 2 topic statistics
publish (``rclcpp::topic_statistics``: the periods between consecutive arrivals that end in the
window, their mean, standard deviation and maximum, and how many there were). ``learn_rate``
folds them into a ``RateEvidence``: the mean rate over the whole recording, the spread of the
per-window rates, the largest gap, and whether the topic is *periodic* (its rate over long
windows varies by less than ``PERIODIC_CV``: a timer or a device's frame clock) or *reactive*
(published in answer to events, which a frequency observer would misjudge). Where the
messages carry the publisher's header stamps, the rate and the gaps are measured on them. For a
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

PERIODIC_CV = 0.3  # the long windows' rate: stddev / mean below this: periodic
STEADY_MESSAGES = 20  # a long window holds this many messages (at least 2 s)
DROP_FACTOR = 1.5  # a sender's period this many times the median: a message was lost
POISSON_SHARE = 0.5  # arrivals: steady when the counts vary less than this share of Poisson
MAX_SILENCE = 10.0  # periods: a longer silence would only slow the detection down
MIN_SAMPLES = 5  # fewer arrivals than this back no rate at all
MESSAGES_PER_WINDOW = 10  # the proposed window holds about this many messages
MIN_WINDOW_S = 0.5
SPREAD_FACTOR = 4.0  # tolerance >= this many standard deviations of the per-window rate
MAX_TOLERANCE = 0.5  # tolerance <= this share of the rate: a silent topic is never ok
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
    """What a topic's arrivals say: ``n`` messages over ``span`` s, the ``rate`` (Hz), the
    per-window rates' spread (Hz, stddev, over ``windows`` windows), ``cv`` (how unsteady: on
    the sender's clock the periods' stddev / mean; on arrivals the long windows' counts'
    variation scaled so that ``PERIODIC_CV`` is ``POISSON_SHARE`` of random events'), the
    largest period (s), and whose ``clock`` measured the periods (``sender``: header stamps;
    ``arrival``)."""

    n: int
    span: float
    rate: float
    spread: float
    cv: float
    max_period: float
    windows: int
    clock: str = "arrival"

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


def window_counts(times: Sequence[float], window: float) -> list[int]:
    """Messages per whole window of ``window`` s from the first (empty windows count)."""
    ts = sorted(times)
    if not ts or window <= 0:
        return []
    n = int((ts[-1] - ts[0]) / window)
    counts = [0] * n
    for t in ts:
        i = int((t - ts[0]) / window)
        if i < n:
            counts[i] += 1
    return counts


def learn_rate(times: Sequence[float], stamps: Sequence[float] = ()) -> RateEvidence | None:
    """The rate evidence of these arrival times (None: fewer than ``MIN_SAMPLES``).

    ``stamps`` (the publisher's header stamps of the same messages, when its type has one)
    are the sender's clock: free of the receiver's scheduling (a busy machine delivers in
    bursts), so the rate is one over their median period (robust to lost messages too), the
    gaps are theirs and periodic means steady periods. On arrivals alone, periodic means a
    count over long windows (``STEADY_MESSAGES`` messages each) far steadier than random
    events': a burst moves a message from one window to the next only. The spread is the per-window
    rate's standard deviation in the window ``propose`` picks, on the arrivals (what the
    daemon's observer counts)."""
    ts = sorted(times)
    if len(ts) < MIN_SAMPLES or ts[-1] <= ts[0]:
        return None
    span = ts[-1] - ts[0]
    sent = sorted(stamps)
    sender = len(sent) >= MIN_SAMPLES and sent[-1] > sent[0]
    clock = sent if sender else ts
    periods = [b - a for a, b in itertools.pairwise(clock)]
    positive = sorted(p for p in periods if p > 0)
    rate = 1.0 / positive[len(positive) // 2] if sender and positive else (len(ts) - 1) / span
    if sender and positive:
        # the sender's periods, a lost message's double period aside: steady or not
        kept = [p for p in positive if p < DROP_FACTOR * positive[len(positive) // 2]]
        mean_p, std_p = _mean_std(kept)
        steadiness = std_p / mean_p
    else:
        # arrivals: a busy receiver bunches them, so count over long windows and compare
        # with events at random (a Poisson count varies by 1/sqrt(n)): steady counts vary
        # far less
        long_w = max(2.0, STEADY_MESSAGES / rate)
        counts = window_counts(ts, long_w)
        per = [c / long_w for c in counts]
        poisson = 1.0 / math.sqrt(rate * long_w)
        steadiness = (_mean_std(per)[1] / rate / poisson * PERIODIC_CV / POISSON_SHARE
                      if len(per) >= 2 else 0.0)
    w = choose_window(rate)
    rates = [c / w for c in window_counts(ts, w)] or [rate]
    _, spread = _mean_std(rates)
    return RateEvidence(len(ts), span, rate, spread, steadiness, max(periods), len(rates),
                        "sender" if sender else "arrival")


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
    silence = min(MAX_SILENCE, max(MIN_SILENCE, math.ceil(GAP_MARGIN * gap)))
    rate = _round(ev.rate)
    window = max(window, _round(2.0 / rate + 0.005))  # the loader wants >= 2 messages a window
    return RateProposal(rate, _round(tolerance), window, float(silence))
