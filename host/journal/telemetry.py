"""Downsampling channel currents for the journal: 100 Hz readings in, 1 Hz summaries out.

The board samples every channel at about 100 Hz; journaling that would grow the file by
hundreds of megabytes an hour and tell the timeline nothing more. ``TelemetryDownsampler``
accumulates the readings of one period (``period_s``, 1 s by default) per channel and, when a
reading arrives at or after the period's end, hands back one ``Telemetry`` entry with the
count, mean, minimum, maximum and last current of each channel that reported. Time is passed in
(the daemon's monotonic time of each reading), so the downsampler is a pure value: the same
readings give the same summaries, on the wall clock or a simulated one. A gap longer than a
period (the link was down) starts a fresh period at the next reading rather than emitting empty
summaries; ``flush`` hands back the partial period at shutdown.
"""

from __future__ import annotations

import logging
from collections.abc import Mapping
from dataclasses import dataclass

from host.events import ChannelSummary, Telemetry

log = logging.getLogger(__name__)


@dataclass
class _Acc:
    samples: int = 0
    total: float = 0.0
    low: float = float("inf")
    high: float = float("-inf")
    last: float = 0.0

    def add(self, ma: float) -> None:
        self.samples += 1
        self.total += ma
        self.low = min(self.low, ma)
        self.high = max(self.high, ma)
        self.last = ma


class TelemetryDownsampler:
    """Per-channel min/mean/max/last over fixed periods of the caller's monotonic time."""

    def __init__(self, period_s: float = 1.0) -> None:
        if period_s <= 0:
            raise ValueError(f"period_s must be positive, not {period_s}")
        self.period_s = period_s
        self._start: float | None = None
        self._acc: dict[int, _Acc] = {}

    def add(self, now: float, currents_ma: Mapping[int, float]) -> Telemetry | None:
        """Add one reading of some channels at ``now``; a finished period's summary, if any.

        The reading that closes a period belongs to the next one.
        """
        summary: Telemetry | None = None
        if self._start is None:
            self._start = now
        elif now >= self._start + self.period_s:
            summary = self._summary()
            # keep periods aligned unless the gap was longer than one period
            nxt = self._start + self.period_s
            self._start = nxt if now < nxt + self.period_s else now
            self._acc = {}
        for channel, ma in currents_ma.items():
            self._acc.setdefault(channel, _Acc()).add(float(ma))
        return summary

    def flush(self) -> Telemetry | None:
        """The summary of the current, unfinished period (None if it has no readings)."""
        summary = self._summary()
        self._start = None
        self._acc = {}
        return summary

    def _summary(self) -> Telemetry | None:
        if not self._acc:
            return None
        return Telemetry(self.period_s, tuple(
            ChannelSummary(ch, a.samples, a.total / a.samples, a.low, a.high, a.last)
            for ch, a in sorted(self._acc.items())))
