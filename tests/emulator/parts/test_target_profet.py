"""Rev C as flashed: its description (``firmware/boards/rev_c.py``) builds, through
``firmware.hal.target.build``, the smart-switch driver (``firmware/hal/profet.py``) on five
PROFET+2 models whose IS pins join one sense node read by the world's ADC; what the driver
reads, and what the board answers to each part fault.

Runs under pytest and under the real MicroPython (``micropython tests/mpy_run.py
tests/emulator/parts``).
"""

import unittest

from emulator.parts.wiring import wire
from emulator.parts.world import World, install
from firmware import boards
from firmware.hal import LOW, NO_READING, TRIPPED
from firmware.hal.storage import MemStorage
from protocol.constants import (
    EV_RANGE,
    EV_TRIP,
    EV_WARNING,
    F_LOW,
    F_OPEN_LOAD,
    F_SENSOR,
    F_SHORT,
    NOT_FAULTS,
    ST_ON,
)
from tests.emulator.parts.test_machine import target_on
from tests.emulator.parts.test_target_ina226 import BoardBench

RATED_MA = 3000


class Bench(BoardBench):
    """Rev C: ten channels on five dual smart switches, every IS into one node."""

    def __init__(self, load_a=None):
        self.b = b = boards.load("rev-c")
        self.n = n = b["channels"]
        self.w = w = install(World())
        self.load_a = list(load_a or [0.5 + 0.25 * ch for ch in range(n)])
        self.closed = [False] * n
        sensed = wire(w, b, self)
        self.parts = [sensed[2 * d][0] for d in range(n // 2)]
        w.wire_adc(b["vin"]["adc_pin"], lambda: 24.0 / 11)
        self.hal = target_on(w).build(b, MemStorage())
        self.board = None
        self.cursor = 0

    def load(self, ch):
        return lambda t: self.load_a[ch]

    def drive(self, ch, level):
        self.closed[ch] = bool(level)


class DriverTest(unittest.TestCase):
    def test_readings_within_the_parts_band_and_the_adc(self):
        b = Bench()
        b.boot()
        for ch, c in enumerate(b.board.channels):
            self.assertEqual(c.state, ST_ON)
            want = b.load_a[ch] * 1000
            # the part's kILIS band (20 % at 0.5 A, 5 % at 2.5 A and up) and about 40 mA of
            # ADC (12 bit, ENOB 8.7: 13 mA a count over 300 Ohm)
            self.assertLess(abs(c.current_ma - want), want * 0.21 + 60)
        self.assertEqual(b.hal.report()[3], "ch3 part1.1 profet ok")

    def test_a_small_load_is_low_not_measured_not_open_load(self):
        b = Bench()
        b.load_a[2] = 0.03  # 30 mA: under the switch's accurate range
        b.boot()
        b.events()
        out = [0] * 10
        b.hal.read_currents_ma(out)
        self.assertEqual(out[2], LOW)
        b.run(10000)  # longer than open_load_ms
        ch = b.board.channels[2]
        self.assertEqual(ch.state, ST_ON)
        self.assertEqual(ch.current_ma, 0)
        self.assertFalse(ch.live & F_OPEN_LOAD)
        self.assertFalse(ch.live & F_SENSOR)  # low is not a sensor fault either
        self.assertFalse([e for e in b.events() if e[1] == EV_WARNING and e[2] == 2])

    def test_low_not_measured_is_a_live_flag_the_host_is_told_of(self):
        """The ``low`` flag (PROTOCOL.md section 10): live from the first LOW reading, with a
        range EVENT; never sticky, never a fault; ended by 50 measured readings in a row."""
        b = Bench()
        b.load_a[2] = 0.03
        b.boot()
        ch = b.board.channels[2]
        self.assertTrue(ch.live & F_LOW)
        self.assertFalse(ch.sticky & F_LOW)
        self.assertFalse(ch.live & ~NOT_FAULTS)  # nothing is wrong with it
        self.assertFalse(b.board.channels[3].live & F_LOW)  # 1.25 A: measured
        said = [(e[5], e[6]) for e in b.events() if e[1] == EV_RANGE and e[2] == 2]
        self.assertEqual(said, [(F_LOW, 0)])  # once, however many low readings followed
        b.load_a[2] = 1.0  # measured again: the flag waits for 50 readings in a row
        b.run(200)
        self.assertTrue(ch.live & F_LOW)
        b.run(600)
        self.assertFalse(ch.live & F_LOW)
        said = [(e[5], e[6] > 500) for e in b.events() if e[1] == EV_RANGE and e[2] == 2]
        self.assertEqual(said, [(0, True)])
        b.load_a[2] = 0.03
        b.run(20)
        self.assertTrue(ch.live & F_LOW)

    def test_a_disconnected_load_while_off_is_seen_as_open_load_off(self):
        b = Bench()
        b.boot()
        b.board.switch(5, False)
        b.parts[2].inject("open_load", 1)
        b.run(20)
        self.assertTrue(b.hal.ina.open_off[5])
        self.assertFalse(b.hal.ina.open_off[4])


class PartFaultTest(unittest.TestCase):
    def test_a_short_is_the_switchs_fault_flag_and_the_channel_trips(self):
        b = Bench()
        b.boot()
        b.events()
        b.parts[3].inject("short", 0)  # channel 6
        out = [0] * 10
        b.hal.read_currents_ma(out)
        self.assertEqual(out[6], TRIPPED)  # a flag, not I_IS(FAULT) x kILIS (20-48 A)
        b.run(100)
        trips = [e for e in b.events() if e[1] == EV_TRIP and e[2] == 6]
        self.assertTrue(trips)
        self.assertEqual(trips[0][5], F_SHORT)
        self.assertEqual(trips[0][6], RATED_MA * 3)
        self.assertNotEqual(b.board.channels[6].state, ST_ON)
        self.assertEqual(b.board.channels[7].state, ST_ON)  # the part's other channel works
        b.parts[3].clear()
        b.run(5000)  # the retry: IN low cleared the latch, IN high switches on again
        self.assertEqual(b.board.channels[6].state, ST_ON)
        self.assertTrue(b.parts[3].on[0])

    def test_over_temperature_trips_the_channel(self):
        b = Bench()
        b.boot()
        b.parts[0].inject("overtemp", 1)
        b.run(100)
        self.assertNotEqual(b.board.channels[1].state, ST_ON)
        self.assertEqual(b.board.channels[0].state, ST_ON)

    def test_a_stuck_sense_node_blinds_the_board_at_boot(self):
        b = Bench()
        b.parts[1].set_in(0, 1)
        b.parts[1].inject("overtemp", 0)  # its fault level on IS ...
        b.parts[1].den = 1  # ... driven whatever its DEN pin says
        b.w.set_time(b.w.now_us + 1000)
        b.hal.ina.setup()
        self.assertIn("sense node driven", b.hal.report()[0])
        out = [0] * 10
        b.hal.read_currents_ma(out)
        self.assertEqual(out, [NO_READING] * 10)  # every channel: F_SENSOR, switches kept


def read_script(python):
    """Rev C's driver (no board: the script switches the channels) through switchings and
    every part fault, per tick: what it read, ``open_off``, ``faults`` and each part's state;
    and every call it made of the pins, the ADC and ``sleep_us``, in order (one int each).
    ``python``: by the loop in Python (``fast`` off), else by ``firmware.fast.profet_read``."""
    b = Bench(load_a=[0.5, 0.03, 2.0, 0.0, 1.25, 3.0, 0.75, 0.06, 1.5, 4.0])
    hal = b.hal
    bank = hal.ina
    if python:
        bank.fast = False
    log = []

    def logged(obj, name, tag):
        real = getattr(obj, name)

        def call(*args):
            got = real(*args)
            log.append(tag * 1000000 + (args[0] if args else 500000 + (got or 0)))
            return got
        setattr(obj, name, call)

    for d, pin in enumerate(bank.den):
        logged(pin, "value", 1 + d)
    logged(bank.dsel, "value", 10)
    logged(bank.adc, "read_u16", 11)
    logged(bank, "sleep_us", 12)
    for ch, pin in enumerate(hal.en):
        logged(pin, "value", 20 + ch)
    bank.bind()  # the driver's bound methods: the wrapped ones
    p = b.parts
    script = {
        0: lambda: [hal.set_switch(ch, ch != 9) for ch in range(10)],
        3: lambda: p[3].inject("short", 0),  # channel 6: latched off, the fault level
        5: lambda: hal.set_switch(6, False),  # IN low: the fault level still (the counter)
        7: lambda: p[2].inject("open_load", 1),  # channel 5, on: nothing drawn
        8: lambda: hal.set_switch(5, False),  # off: open load in the off state
        10: lambda: p[0].inject("overtemp", 1),  # channel 1 (low load) latched off
        12: lambda: p[4].inject("open_load", 1),  # channel 9, off all along
        14: lambda: [part.clear() for part in p],
        15: lambda: [hal.set_switch(ch, True) for ch in (5, 6, 9)],
        18: lambda: [hal.set_switch(ch, False) for ch in range(0, 10, 3)],
    }
    out = [0] * b.n
    seen = []
    for tick in range(24):
        b.w.set_time(b.w.now_us + 10000)
        if tick in script:
            script[tick]()
        hal.read_currents_ma(out)
        seen.append((list(out), list(bank.open_off), bank.faults,
                     [(q.inp[:], q.on[:], q.latched[:], q.counter[:], q.den, q.dsel)
                      for q in p]))
    return log, seen


class ReadPathTest(unittest.TestCase):
    """The driver's read (``firmware.fast.profet_read``) against its loop in Python, the same
    parts and faults: the same calls of the pins, the ADC and the wait in the same order, the
    same values, codes and state after each tick."""

    def test_the_read_is_the_python_loops_call_for_call(self):
        ref_log, ref = read_script(True)
        log, got = read_script(False)
        for i in range(len(ref)):
            self.assertEqual(got[i], ref[i], f"tick {i}")
        self.assertEqual(len(log), len(ref_log))
        for i in range(len(ref_log)):
            self.assertEqual(log[i], ref_log[i], f"call {i}")
        # the script reaches every outcome: a current, LOW, TRIPPED, 0 at the fault level with
        # IN low, open load off
        outs = ref[4][0] + ref[6][0] + ref[9][0]
        for want in (LOW, TRIPPED, 0):
            self.assertIn(want, outs)
        self.assertTrue(any(v > 0 for v in outs))
        self.assertTrue(ref[9][1][5])
        self.assertGreater(ref[4][3][3][3][0], 0)  # part 3's restart counter, then IN low:
        self.assertEqual(ref[5][0][6], 0)  # the fault level read with IN low
        self.assertGreaterEqual(ref[-1][2], 2)  # faults

    def test_the_fast_read_is_taken_and_its_fraction_reduced(self):
        bank = Bench().hal.ina
        self.assertTrue(bank.fast)
        # 3,300,000 uV / (2 x 4095 x 300 Ohm) = 1100 / 819: 8190 x 1100 fits 31 bits
        self.assertEqual(list(bank.par), [20, 1100, 819, 3800, 1500, 4785, 100])
