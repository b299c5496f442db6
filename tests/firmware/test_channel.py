"""Channel protection on the real firmware with a simulated clock: each rule, in its window."""

import unittest

from benchmarks._rigs.testhal import Rig
from firmware.channel import TRANSITIONS, X_CLEAR, X_OFF, X_ON, X_SHED
from protocol.constants import (
    E_LATCHED,
    E_SWITCH_FAULT,
    EV_TRIP,
    EV_WARNING,
    F_INRUSH,
    F_OPEN_LOAD,
    F_OVERLOAD,
    F_SHORT,
    F_STUCK_OFF,
    F_STUCK_ON,
    ST_FAULTED,
    ST_INRUSH,
    ST_LATCHED,
    ST_OFF,
    ST_ON,
    ST_TRIPPED,
)

RATED = 1000


def rig(**fields):
    c = {"rated_ma": RATED}
    c.update(fields)
    return Rig(channels={0: c})


def on_and_settle(r, ma):
    """Switch channel 0 on with a normal load, let the inrush window pass, then set ``ma``."""
    r.hal.load_ma[0] = RATED // 2
    r.board.switch(0, True)
    r.run(200)
    assert r.state(0) == ST_ON
    r.hal.load_ma[0] = ma


class TableTest(unittest.TestCase):
    def test_every_command_has_an_entry_in_every_state(self):
        for st in (ST_OFF, ST_INRUSH, ST_ON, ST_TRIPPED, ST_LATCHED, ST_FAULTED):
            for x in (X_ON, X_OFF, X_CLEAR, X_SHED):
                self.assertIn((st, x), TRANSITIONS)

    def test_a_miss_is_an_error(self):
        r = rig()
        with self.assertRaises(KeyError):
            r.board.channels[0].fire(99, 0)


class InrushTest(unittest.TestCase):
    def test_normal_inrush_does_not_trip(self):
        r = rig()
        r.hal.load_ma[0] = 39 * RATED // 10  # 3.9x: above the instant trip, below inrush
        r.board.switch(0, True)
        r.run(90)
        self.assertEqual(r.state(0), ST_INRUSH)
        r.hal.load_ma[0] = RATED
        r.run(5000)
        self.assertEqual(r.state(0), ST_ON)
        self.assertEqual(r.board.channels[0].sticky, 0)

    def test_inrush_above_limit_trips_at_once(self):
        r = rig()
        r.hal.load_ma[0] = 5 * RATED
        r.board.switch(0, True)
        t = r.run_until(lambda: r.state(0) != ST_INRUSH, 1000)
        self.assertLessEqual(t, 30)
        self.assertEqual(r.state(0), ST_TRIPPED)
        self.assertTrue(r.board.channels[0].sticky & F_INRUSH)

    def test_inrush_window_ends_after_inrush_ms(self):
        r = rig(inrush_ms=300)
        r.hal.load_ma[0] = RATED
        r.board.switch(0, True)
        t = r.run_until(lambda: r.state(0) == ST_ON, 1000)
        self.assertGreaterEqual(t, 300)
        self.assertLessEqual(t, 320)


class InstantTripTest(unittest.TestCase):
    def test_short_trips_within_two_samples(self):
        r = rig()
        on_and_settle(r, 20 * RATED)
        t = r.run_until(lambda: r.state(0) == ST_TRIPPED, 1000)
        self.assertGreaterEqual(t, 10)
        self.assertLessEqual(t, 20)
        self.assertTrue(r.board.channels[0].live & F_SHORT)
        self.assertFalse(r.hal.cmd[0])

    def test_one_sample_spike_does_not_trip(self):
        r = rig()
        on_and_settle(r, 5 * RATED)
        r.run(10)
        r.hal.load_ma[0] = RATED
        r.run(100)
        self.assertEqual(r.state(0), ST_ON)

    def test_trip_event_carries_fault_and_current(self):
        r = rig()
        on_and_settle(r, 4 * RATED)
        r.events()
        r.run(50)
        trips = [e for e in r.events() if e[1] == EV_TRIP]
        self.assertEqual(len(trips), 1)
        self.assertEqual(trips[0][5], F_SHORT)
        self.assertEqual(trips[0][6], 4 * RATED)


class OverloadTest(unittest.TestCase):
    def trip_time(self, factor_x10):
        r = rig()
        on_and_settle(r, RATED * factor_x10 // 10)
        return r.run_until(lambda: r.state(0) == ST_TRIPPED, 10000), r

    def test_i2t_curve(self):
        for fx10, lo, hi in ((15, 2700, 3300), (20, 1000, 1250), (29, 380, 480)):
            with self.subTest(factor=fx10):
                t, r = self.trip_time(fx10)
                self.assertGreaterEqual(t, lo)
                self.assertLessEqual(t, hi)
                self.assertTrue(r.board.channels[0].live & F_OVERLOAD)

    def test_no_trip_below_start(self):
        t, _ = self.trip_time(11)
        self.assertEqual(t, -1)

    def test_heat_cools_down(self):
        r = rig()
        on_and_settle(r, 2 * RATED)
        r.run(800)  # most of the way to a trip
        r.hal.load_ma[0] = RATED // 2
        r.run(3000)
        self.assertEqual(r.board.channels[0].heat, 0)
        r.hal.load_ma[0] = 2 * RATED
        t = r.run_until(lambda: r.state(0) == ST_TRIPPED, 5000)
        self.assertGreater(t, 1000)


class RetryTest(unittest.TestCase):
    def test_overload_retries_after_1_2_5_s_then_latches(self):
        r = rig()
        on_and_settle(r, 3 * RATED - 100)
        for delay in (1000, 2000, 5000):
            self.assertGreaterEqual(r.run_until(lambda: r.state(0) == ST_TRIPPED, 2000), 0)
            t = r.run_until(lambda: r.state(0) == ST_INRUSH, 10000)
            self.assertGreaterEqual(t, delay - 10)
            self.assertLessEqual(t, delay + 10)
        self.assertGreaterEqual(r.run_until(lambda: r.state(0) == ST_LATCHED, 2000), 0)
        r.run(60000)
        self.assertEqual(r.state(0), ST_LATCHED)
        self.assertEqual(r.board.channel_status(0)[6], 4)  # trips

    def test_short_retries_once_then_latches(self):
        r = rig()
        on_and_settle(r, 10 * RATED)
        r.run_until(lambda: r.state(0) == ST_TRIPPED, 100)
        t = r.run_until(lambda: r.state(0) == ST_INRUSH, 5000)
        self.assertGreaterEqual(t, 990)
        self.assertLessEqual(t, 1010)
        t = r.run_until(lambda: r.state(0) == ST_LATCHED, 100)
        self.assertGreaterEqual(t, 0)

    def test_latched_refuses_on_until_cleared(self):
        r = rig(short_retries=0)
        on_and_settle(r, 10 * RATED)
        r.run(50)
        self.assertEqual(r.state(0), ST_LATCHED)
        err, st, phys = r.board.switch(0, True)
        self.assertEqual((err, st, phys), (E_LATCHED, ST_LATCHED, False))
        self.assertEqual(r.state(0), ST_LATCHED)
        r.hal.load_ma[0] = RATED // 2
        err, st, _ = r.board.clear(0)
        self.assertEqual((err, st), (0, ST_OFF))
        self.assertEqual(r.board.channels[0].sticky, 0)
        err, st, phys = r.board.switch(0, True)
        self.assertEqual((err, st, phys), (0, ST_INRUSH, True))
        r.run(200)
        self.assertEqual(r.state(0), ST_ON)

    def test_retry_counter_resets_after_a_quiet_minute(self):
        r = rig()
        on_and_settle(r, 10 * RATED)
        r.run_until(lambda: r.state(0) == ST_TRIPPED, 100)
        r.hal.load_ma[0] = RATED // 2
        r.run(1500)
        self.assertEqual(r.state(0), ST_ON)
        self.assertEqual(r.board.channel_status(0)[7], 1)
        r.run(58000)  # 59.5 s after the trip
        self.assertEqual(r.board.channel_status(0)[7], 1)
        r.run(1000)
        self.assertEqual(r.board.channel_status(0)[7], 0)
        r.hal.load_ma[0] = 10 * RATED  # a new short gets its retry again
        r.run(50)
        self.assertEqual(r.state(0), ST_TRIPPED)

    def test_off_cancels_a_retry(self):
        r = rig()
        on_and_settle(r, 10 * RATED)
        r.run(50)
        self.assertEqual(r.board.switch(0, False)[:2], (0, ST_OFF))
        r.run(3000)
        self.assertEqual(r.state(0), ST_OFF)


class OpenLoadTest(unittest.TestCase):
    def test_open_load_warns_after_1_s_and_clears(self):
        r = rig()
        on_and_settle(r, 5)
        r.events()
        t = r.run_until(lambda: r.board.channels[0].live & F_OPEN_LOAD, 3000)
        self.assertGreaterEqual(t, 990)
        self.assertLessEqual(t, 1020)
        self.assertEqual(r.state(0), ST_ON)  # a warning, not a trip
        self.assertTrue(any(e[1] == EV_WARNING and e[5] == F_OPEN_LOAD for e in r.events()))
        r.hal.load_ma[0] = RATED // 2
        r.run(20)
        self.assertFalse(r.board.channels[0].live & F_OPEN_LOAD)
        self.assertTrue(r.board.channels[0].sticky & F_OPEN_LOAD)

    def test_auto_threshold_is_one_percent_of_rated(self):
        r = Rig(channels={0: {"rated_ma": 10000}})
        r.hal.load_ma[0] = 90  # above 20 mA but below 1 % of 10 A
        r.board.switch(0, True)
        r.run(1200)
        self.assertTrue(r.board.channels[0].live & F_OPEN_LOAD)


class StuckSwitchTest(unittest.TestCase):
    def test_stuck_on_faults_after_200_ms(self):
        r = rig()
        on_and_settle(r, RATED // 2)
        r.hal.stuck[0] = True
        r.board.switch(0, False)
        t = r.run_until(lambda: r.state(0) == ST_FAULTED, 1000)
        self.assertGreaterEqual(t, 190)
        self.assertLessEqual(t, 220)
        self.assertTrue(r.board.channels[0].sticky & F_STUCK_ON)
        self.assertEqual(r.board.switch(0, True)[0], E_SWITCH_FAULT)

    def test_stuck_on_below_threshold_is_fine(self):
        r = rig()
        on_and_settle(r, 40)
        r.hal.stuck[0] = True
        r.board.switch(0, False)
        r.run(1000)
        self.assertEqual(r.state(0), ST_OFF)

    def test_stuck_off_faults(self):
        r = rig()
        r.hal.stuck[0] = False
        r.hal.load_ma[0] = RATED
        r.board.switch(0, True)
        t = r.run_until(lambda: r.state(0) == ST_FAULTED, 1000)
        self.assertGreaterEqual(t, 0)
        self.assertLessEqual(t, 30)
        self.assertTrue(r.board.channels[0].live & F_STUCK_OFF)
        r.hal.stuck[0] = None
        self.assertEqual(r.board.clear(0)[:2], (0, ST_OFF))
        self.assertEqual(r.board.switch(0, True)[:3], (0, ST_INRUSH, True))
