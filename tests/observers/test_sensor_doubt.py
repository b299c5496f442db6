"""A sensor the board doubts (``F_SENSOR``: it gives no reading, or reads current with the switch
open) is a fault of the sensor, not of the device (issues 25 item 8 and 27 item 4): the hardware
observer stops judging that device's current (``in_band`` retracted: unknown, never ``over`` or
``under`` from a sensor that lies) and says why, until the board reads it again."""

from __future__ import annotations

import logging

import pytest

from host.board.types import BoardEvent
from host.observers import HardwareObserver, Retraction
from protocol.constants import EV_FAULT, EV_WARNING, F_OVERLOAD, F_SENSOR, ST_ON
from tests.observers.test_hardware import (
    HOKUYO,
    JAGUAR,
    feed_readings,
    healthy_hokuyo,
    lits,
    state,
)


def fault(ch: int, flags: int, kind: int = EV_FAULT) -> BoardEvent:
    return BoardEvent(0.0, 1, 6, 200, kind, ch, ST_ON, ST_ON, flags, 0, 0)


def test_a_sensor_fault_makes_the_current_unknown_not_bad(caplog: pytest.LogCaptureFixture
                                                          ) -> None:
    h = healthy_hokuyo()
    with caplog.at_level(logging.WARNING):
        out = h.feed(fault(3, F_SENSOR), 2.0)
    assert [u.atom for u in out if isinstance(u, Retraction)] == ["in_band(hokuyo)"]
    assert "in_band(hokuyo)" not in h.asserted
    assert "sensor" in caplog.text and "hokuyo" in caplog.text
    # the board reads 0 mA for it now (live fault bit set): no band, no under-current
    out = feed_readings(h, 2.01, 10, {3: 0}, faults=1 << 3)
    assert not any(a.startswith("in_band") for a, _ in lits(out))
    assert h.asserted["on(hokuyo)"] is True and h.asserted["tripped(hokuyo)"] is False
    assert "hokuyo" in h.doubted


def test_readings_back_judge_the_band_again() -> None:
    h = healthy_hokuyo()
    h.feed(fault(3, F_SENSOR), 2.0)
    feed_readings(h, 2.01, 3, {3: 0}, faults=1 << 3)
    h.feed(fault(3, 0), 2.1)  # the board: the sensor reads again
    assert "hokuyo" not in h.doubted
    feed_readings(h, 2.11, 3, {3: 500}, seq0=200)
    assert h.asserted["in_band(hokuyo)"] is True


def test_a_state_with_the_sensor_flag_doubts_it_at_once() -> None:
    h = HardwareObserver({"hokuyo": HOKUYO, "jaguar": JAGUAR}, link_timeout=0.05, settle=3)
    h.feed(state({3: (True, ST_ON, F_SENSOR)}), 1.0)
    feed_readings(h, 1.01, 5, {3: 6000}, faults=1 << 3)
    assert "in_band(hokuyo)" not in h.asserted
    h.feed(state({3: (True, ST_ON, 0)}), 1.1)
    feed_readings(h, 1.11, 3, {3: 500}, seq0=200)
    assert h.asserted["in_band(hokuyo)"] is True


def test_a_protected_overload_is_told(caplog: pytest.LogCaptureFixture) -> None:
    h = healthy_hokuyo()
    with caplog.at_level(logging.WARNING):
        h.feed(fault(3, F_OVERLOAD, EV_WARNING), 2.0)
    assert "overload" in caplog.text and "hokuyo" in caplog.text
