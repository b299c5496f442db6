"""The PROFET+2 model (BTS7008-2EPA class) against the data sheet's diagnosis numbers: kILIS and
its band, the fault and open-load-off levels on IS, DEN/DSEL multiplexing, the settling time,
the latch and the restart counter.

Runs under pytest and under the real MicroPython (``micropython tests/mpy_run.py
tests/emulator/parts``).
"""

import unittest

from emulator.parts import profet as P
from emulator.parts.profet import Profet


class Clock:
    def __init__(self):
        self.t = 0

    def __call__(self):
        return self.t


def part(a0=1.0, a1=2.0, seed=1):
    clock = Clock()
    amps = [a0, a1]
    p = Profet([lambda t: amps[0], lambda t: amps[1]], seed=seed, clock=clock)
    return p, clock, amps


def sensed(p, clock, ch):
    p.set_dsel(ch)
    p.set_den(1)
    clock.t += P.SETTLE_US
    return p.is_current()


class SenseTest(unittest.TestCase):
    def test_is_is_the_load_over_kilis_within_the_band(self):
        for seed in range(1, 30):
            p, clock, _ = part(1.0, 5.0, seed)
            p.set_in(0, 1)
            p.set_in(1, 1)
            k1 = 1.0 / sensed(p, clock, 0)
            k5 = 5.0 / sensed(p, clock, 1)
            self.assertLessEqual(abs(k1 / P.K_ILIS - 1), 0.08 + 1e-9)
            self.assertLessEqual(abs(k5 / P.K_ILIS - 1), 0.04 + 1e-9)

    def test_the_band_is_wide_at_low_current_and_narrow_at_high(self):
        self.assertAlmostEqual(P.tolerance(0.05), 0.34)
        self.assertAlmostEqual(P.tolerance(0.01), 0.34)
        self.assertAlmostEqual(P.tolerance(5.0), 0.04)
        self.assertAlmostEqual(P.tolerance(8.0), 0.04)
        self.assertGreater(P.tolerance(0.1), P.tolerance(1.0))

    def test_each_part_keeps_its_own_error(self):
        p, clock, _ = part(2.0, 2.0, 7)
        self.assertEqual(sensed(p, clock, 0), 0.0)  # IN low, no fault: nothing on IS
        p.set_in(0, 1)
        first = sensed(p, clock, 0)
        p.set_den(0)
        second = sensed(p, clock, 0)
        self.assertEqual(first, second)
        q, qclock, _ = part(2.0, 2.0, 8)
        q.set_in(0, 1)
        self.assertNotEqual(sensed(q, qclock, 0), first)

    def test_den_low_is_high_impedance_and_dsel_picks_the_channel(self):
        p, clock, _ = part(1.0, 4.0)
        p.set_in(0, 1)
        p.set_in(1, 1)
        self.assertEqual(p.is_current(), 0.0)
        self.assertLess(sensed(p, clock, 0), sensed(p, clock, 1) / 2)

    def test_a_new_selection_settles_in_t_sis(self):
        p, clock, _ = part(1.0, 4.0)
        p.set_in(1, 1)
        p.set_den(1)
        p.set_dsel(1)
        clock.t += P.SETTLE_US - 1
        self.assertEqual(p.is_current(), 0.0)
        clock.t += 1
        self.assertGreater(p.is_current(), 0.0)

    def test_open_load_in_on_reads_at_most_i_is_en(self):
        p, clock, _ = part(0.02, 0.0)
        p.set_in(0, 1)
        self.assertLessEqual(sensed(p, clock, 0), P.I_IS_EN_A)


class FaultTest(unittest.TestCase):
    def test_a_short_latches_the_output_off_with_the_fault_level(self):
        p, clock, _ = part()
        p.set_in(0, 1)
        p.set_in(1, 1)
        p.inject("short", 0)
        self.assertFalse(p.on[0])
        self.assertEqual(p.counter[0], 1)
        i = sensed(p, clock, 0)
        self.assertGreaterEqual(i, 4.4e-3)
        self.assertLessEqual(i, 10e-3)
        self.assertGreater(sensed(p, clock, 1), 0.0)  # the other channel works on
        self.assertTrue(p.on[1])

    def test_in_low_clears_the_latch_and_den_with_in_low_the_counter(self):
        p, clock, _ = part()
        p.set_in(0, 1)
        p.inject("short", 0)
        p.clear()
        p.set_in(0, 1)  # still high: stays latched
        self.assertFalse(p.on[0])
        p.set_in(0, 0)
        self.assertGreaterEqual(sensed(p, clock, 0), 4.4e-3)  # the counter still says so
        p.set_den(0)  # DEN falling with IN low
        self.assertEqual(p.counter[0], 0)
        self.assertEqual(sensed(p, clock, 0), 0.0)
        p.set_in(0, 1)
        self.assertTrue(p.on[0])

    def test_the_counter_stops_restarts_at_its_limit(self):
        p, _, _ = part()
        p.inject("short", 0)
        for _ in range(P.COUNTER_MAX):
            p.set_in(0, 1)
            p.set_in(0, 0)
        self.assertEqual(p.counter[0], P.COUNTER_MAX)
        p.clear()
        p.set_in(0, 1)
        self.assertFalse(p.on[0])  # latched for good until DEN clears the counter

    def test_over_temperature_latches_too(self):
        p, clock, _ = part()
        p.set_in(1, 1)
        p.inject("overtemp", 1)
        self.assertFalse(p.on[1])
        self.assertGreaterEqual(sensed(p, clock, 1), 4.4e-3)

    def test_open_load_in_the_off_state(self):
        p, clock, _ = part()
        p.inject("open_load", 0)
        i = sensed(p, clock, 0)
        self.assertGreaterEqual(i, 1.9e-3)
        self.assertLessEqual(i, 3.5e-3)
        p.set_in(0, 1)
        self.assertEqual(sensed(p, clock, 0), 0.0)  # on: nothing flows, IS near 0

    def test_an_unknown_fault_is_refused(self):
        p, _, _ = part()
        self.assertRaises(ValueError, p.inject, "melted", 0)
