"""The downsampler turns 100 Hz readings into 1 Hz per-channel summaries on the given clock."""

from __future__ import annotations

import pytest

from host.journal import ChannelSummary, Telemetry, TelemetryDownsampler


def test_100_hz_readings_become_one_summary_a_second() -> None:
    ds = TelemetryDownsampler(period_s=1.0)
    out: list[Telemetry] = []
    for k in range(350):  # 3.5 s at 100 Hz; channel 1 ramps, channel 2 constant
        t = ds.add(k / 100, {1: float(k % 100), 2: 250.0})
        if t is not None:
            out.append(t)
    assert len(out) == 3
    first = out[0]
    assert first.period_s == 1.0
    assert first.channels == (ChannelSummary(1, 100, 49.5, 0.0, 99.0, 99.0),
                              ChannelSummary(2, 100, 250.0, 250.0, 250.0, 250.0))
    rest = ds.flush()
    assert rest is not None and rest.channels[0].samples == 50
    assert ds.flush() is None


def test_a_gap_starts_a_new_period_instead_of_emitting_empty_ones() -> None:
    ds = TelemetryDownsampler(period_s=1.0)
    assert ds.add(0.0, {0: 1.0}) is None
    assert ds.add(0.5, {0: 3.0}) is None
    summary = ds.add(10.0, {0: 7.0})  # the link was down for 9.5 s
    assert summary is not None and summary.channels == (ChannelSummary(0, 2, 2.0, 1.0, 3.0, 3.0),)
    assert ds.add(10.9, {0: 9.0}) is None  # the new period started at 10.0
    after = ds.add(11.0, {0: 1.0})
    assert after is not None and after.channels[0].samples == 2


def test_channels_that_report_only_sometimes_are_summarised_when_they_do() -> None:
    ds = TelemetryDownsampler(period_s=0.5)
    ds.add(0.0, {4: 10.0})
    ds.add(0.1, {5: 20.0})
    summary = ds.add(0.5, {})
    assert summary is not None
    assert [c.channel for c in summary.channels] == [4, 5]
    with pytest.raises(ValueError):
        TelemetryDownsampler(period_s=0)
