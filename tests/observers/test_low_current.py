"""A current the board could not measure (its ``low`` flag: below the sensing part's accurate
range, as rev C's smart-switch sense is under 100 mA; the reading is 0) is *low, not measured*
(issue 27 item 4): the hardware observer leaves that device's current unknown (``in_band``
retracted, never ``under``), keeps its ``tripped`` and ``on`` facts, and judges the current
again once the board measures it (PROTOCOL.md section 10)."""

from __future__ import annotations

import logging

import pytest

from host.board.types import BoardEvent, Rebooted
from host.observers import HardwareObserver, Retraction
from protocol.constants import EV_RANGE, F_LOW, ST_ON
from tests.observers.test_hardware import (
    HOKUYO,
    JAGUAR,
    feed_readings,
    healthy_hokuyo,
    lits,
    state,
)


def low(ch: int, flags: int = F_LOW, value: int = 0) -> BoardEvent:
    return BoardEvent(0.0, 1, 6, 200, EV_RANGE, ch, ST_ON, ST_ON, flags, value, 0)


def test_a_low_current_is_unknown_not_under(caplog: pytest.LogCaptureFixture) -> None:
    h = healthy_hokuyo()
    with caplog.at_level(logging.INFO):
        out = h.feed(low(3), 2.0)
    assert [u.atom for u in out if isinstance(u, Retraction)] == ["in_band(hokuyo)"]
    assert "low, not measured" in caplog.text and "hokuyo" in caplog.text
    # the board reads 0 mA for it, with no live fault bit: no band, no under-current
    out = feed_readings(h, 2.01, 10, {3: 0})
    assert not any(a.startswith("in_band") for a, _ in lits(out))
    assert "in_band(hokuyo)" not in h.asserted and "hokuyo" not in h.bands
    assert h.asserted["on(hokuyo)"] is True and h.asserted["tripped(hokuyo)"] is False
    assert h.low == {"hokuyo"} and not h.doubted


def test_measured_again_the_band_is_judged_again() -> None:
    h = healthy_hokuyo()
    h.feed(low(3), 2.0)
    feed_readings(h, 2.01, 3, {3: 0})
    h.feed(low(3, 0, 150), 2.1)  # 150 mA: measured, and under the band of 0.2..1.2 A
    assert not h.low
    feed_readings(h, 2.11, 3, {3: 150}, seq0=200)
    assert h.asserted["in_band(hokuyo)"] is False


def test_a_state_with_low_live_says_it_at_once() -> None:
    h = HardwareObserver({"hokuyo": HOKUYO, "jaguar": JAGUAR}, link_timeout=0.05, settle=3)
    h.feed(state({3: (True, ST_ON, F_LOW)}), 1.0)
    feed_readings(h, 1.01, 5, {3: 0})
    assert "in_band(hokuyo)" not in h.asserted and h.asserted["on(hokuyo)"] is True
    h.feed(state({3: (True, ST_ON, 0)}), 1.1)
    feed_readings(h, 1.11, 3, {3: 500}, seq0=200)
    assert h.asserted["in_band(hokuyo)"] is True


def test_a_reboot_forgets_it() -> None:
    h = healthy_hokuyo()
    h.feed(low(3), 2.0)
    h.feed(Rebooted(2.1, 1, 2, 0, "boot id"), 2.1)
    assert not h.low
