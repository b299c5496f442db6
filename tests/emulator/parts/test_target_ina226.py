"""The shipped HAL's INA226 driver (``firmware/hal/ina226.py`` through ``firmware/hal/target.py``)
against the INA226 models on the parts world, each part fault end to end: what the driver
reads, and what the board (``firmware.board.Board`` on that HAL) answers.

Runs under pytest and under the real MicroPython (``micropython tests/mpy_run.py
tests/emulator/parts``).
"""

import unittest

from emulator.parts import ina226 as I
from emulator.parts import machine
from emulator.parts.ina226 import Ina226
from emulator.parts.world import World, install
from firmware.board import Board
from firmware.hal.ina226 import CONFIG_TICK, calibration
from firmware.hal.storage import MemStorage
from protocol.constants import EV_FAULT, EV_WARNING, F_OPEN_LOAD, F_SENSOR, ST_ON
from tests.emulator.parts.test_machine import target_on

EN = (2, 3, 4)
STATUS = (12, 13, 14)
ADDRS = (0x40, 0x41, 0x42)
SHUNT_OHM = 0.010


class BoardBench:
    """What every revision's bench shares: the switches' nets, the board stepped tick by tick
    on the world's clock, its events read in order. A subclass sets ``w``, ``closed``,
    ``hal``, ``board`` and ``cursor``."""

    def _switch(self, ch):
        def drive(level):
            self.closed[ch] = bool(level)
        return drive

    def _status(self, ch):
        return lambda: self.closed[ch]

    def boot(self, protected=(), rated_ma=3000):
        """Every channel rated ``rated_ma`` and switched on at power-up; 2 s run."""
        cfg = {"channels": [{"name": "c" + str(i), "rated_ma": rated_ma, "powerup": True,
                             "protected": i in protected} for i in range(self.hal.n_channels)]}
        self.board = Board(self.hal, cfg)
        self.board.boot(self.w.now_us // 1000)
        self.run(2000)

    def run(self, ms):
        end = self.w.now_us + ms * 1000
        while self.w.now_us < end:
            self.w.set_time(self.w.now_us + 10000 - self.w.now_us % 10000)
            self.hal.wdt_feed()
            self.board.tick(self.w.now_us // 1000)

    def events(self):
        evs, self.cursor, _ = self.board.events.read(self.cursor, 1000)
        return evs


class Bench(BoardBench):
    """Three channels: switch enable -> load -> shunt -> INA226, on the parts world."""

    def __init__(self, load_a=(0.8, 1.5, 0.3), faults=None):
        self.w = w = install(World())
        self.load_a = list(load_a)
        self.closed = [False] * len(EN)
        self.chips = []
        for ch in range(len(EN)):
            w.wire_output(EN[ch], self._switch(ch))
            w.wire_input(STATUS[ch], self._status(ch))
            chip = Ina226(self._source(ch), seed=ch + 1)
            w.bus(0).attach(ADDRS[ch], chip)
            self.chips.append(chip)
        for ch, (fault, value) in (faults or {}).items():  # already there at power-on
            self.chips[ch].inject(fault, value)
        target = target_on(w)
        self.hal = target.TargetHal(EN, STATUS, i2c=machine.I2C(0, freq=400000, timeout=2000),
                                    ina226_addrs=ADDRS, shunt_uohm=10000,
                                    storage=MemStorage())
        self.board = None
        self.cursor = 0

    def _source(self, ch):
        def source(t_us):
            amps = self.load_a[ch] if self.closed[ch] else 0.0
            return amps * SHUNT_OHM, 24.0
        return source

    def reads(self, ticks=1):
        out = [0] * len(EN)
        for _ in range(ticks):
            self.w.set_time(self.w.now_us + 10000)
            self.hal.read_currents_ma(out)
        return out


class DriverTest(unittest.TestCase):
    def test_boot_checks_ids_and_configures_for_the_tick(self):
        b = Bench()
        for chip in b.chips:
            self.assertEqual(chip.regs[I.CONFIG], CONFIG_TICK)
            self.assertEqual(chip.regs[I.CALIBRATION], 2048)
        self.assertEqual(calibration(10000), 2048)  # 0.00512 / (250 uA x 10 mOhm)
        self.assertLess(I.cycle_us(CONFIG_TICK), 10000)  # (1.1 + 1.1) ms x 4 = 8.8 ms

    def test_a_fresh_sample_every_tick(self):
        b = Bench()
        for ch in range(3):
            b.closed[ch] = True
        self.assertEqual(b.reads(2), [800, 1500, 300])
        before = b.chips[0].conversions
        b.load_a[0] = 2.0
        self.assertEqual(b.reads(2)[0], 2000)
        self.assertGreaterEqual(b.chips[0].conversions - before, 2)

    def test_bus_time_per_tick(self):
        b = Bench()
        bus = b.w.bus(0)
        t = bus.busy_us
        b.reads(1)
        self.assertEqual(bus.busy_us - t, 4 * 120)  # 3 shunt reads and 1 CONFIG check


class PartFaultTest(unittest.TestCase):
    def test_nack_is_a_sensor_fault_and_the_channel_stays_on(self):
        b = Bench()
        b.boot()
        self.assertEqual(b.board.channels[0].state, ST_ON)
        b.events()
        b.chips[0].inject("nack")
        b.run(5000)
        ch = b.board.channels[0]
        self.assertEqual(ch.state, ST_ON)
        self.assertTrue(b.closed[0])
        self.assertTrue(ch.live & F_SENSOR)
        self.assertEqual(b.board.channels[1].current_ma, 1500)  # the others read on
        b.chips[0].clear()
        b.run(100)
        self.assertFalse(ch.live & F_SENSOR)
        self.assertEqual(ch.current_ma, 800)
        said = [e[5] for e in b.events() if e[1] == EV_FAULT and e[2] == 0]
        self.assertEqual(said, [F_SENSOR, 0])

    def test_a_bus_held_low_blinds_every_channel_and_costs_little(self):
        b = Bench()
        b.boot()
        b.chips[2].inject("stuck_low")
        t = b.w.now_us
        b.run(1000)  # 100 ticks: the bus is tried every tenth, each try costs the timeout
        self.assertLess(b.w.now_us - t, 1000000 + 10 * 2000 + 10000)
        for ch in b.board.channels:
            self.assertTrue(ch.live & F_SENSOR)
            self.assertEqual(ch.state, ST_ON)
        b.chips[2].clear()
        b.run(300)
        self.assertEqual([c.current_ma for c in b.board.channels], [800, 1500, 300])
        self.assertFalse(b.board.channels[0].live & F_SENSOR)

    def test_a_chip_reset_is_noticed_and_configured_again(self):
        b = Bench()
        b.boot()
        b.chips[1].inject("reset", now_us=b.w.now_us)
        self.assertEqual(b.chips[1].regs[I.CALIBRATION], 0)
        b.run(100)  # three chips checked in turn: within 3 ticks
        self.assertEqual(b.chips[1].regs[I.CONFIG], CONFIG_TICK)
        self.assertEqual(b.chips[1].regs[I.CALIBRATION], 2048)
        self.assertEqual(b.hal.ina.resets, 1)
        self.assertEqual(b.board.channels[1].current_ma, 1500)

    def test_a_wrong_chip_is_never_trusted(self):
        b = Bench(faults={2: ("die_id", 0x3220)})  # an INA3221 where an INA226 belongs
        b.boot()
        ch = b.board.channels[2]
        self.assertTrue(ch.live & F_SENSOR)
        self.assertEqual(ch.current_ma, 0)
        self.assertEqual(b.chips[2].regs[I.CONFIG], 0x4127)  # never written to
        self.assertEqual(b.board.channels[1].current_ma, 1500)

    def test_stuck_reading_shows_a_frozen_current(self):
        b = Bench()
        b.boot()
        b.chips[0].inject("stuck")
        b.load_a[0] = 2.5
        b.run(1000)
        self.assertEqual(b.board.channels[0].current_ma, 800)  # the board cannot tell

    def test_open_shunt_reads_no_current_and_warns_open_load(self):
        b = Bench()
        b.boot()
        b.events()
        b.chips[0].inject("open_shunt")
        b.run(10000)
        ch = b.board.channels[0]
        self.assertEqual(ch.current_ma, 0)
        self.assertTrue(ch.live & F_OPEN_LOAD)
        self.assertEqual([e[5] for e in b.events() if e[1] == EV_WARNING and e[2] == 0],
                         [F_OPEN_LOAD])

    def test_gain_error_scales_the_current(self):
        b = Bench()
        b.boot()
        b.chips[1].inject("gain", 1.5)
        b.run(100)
        self.assertEqual(b.board.channels[1].current_ma, 2250)

    def test_noise_spreads_the_readings(self):
        b = Bench()
        b.boot()
        b.chips[0].inject("noise", 0.002)  # 2 mV rms per conversion: 100 mA rms after AVG 4
        seen = set()
        for _ in range(50):
            b.run(10)
            seen.add(b.board.channels[0].current_ma)
        self.assertGreater(len(seen), 10)


class ReportTest(unittest.TestCase):
    def test_what_the_board_prints_about_its_sensors_at_boot(self):
        b = Bench(faults={1: ("nack", True), 2: ("die_id", 0x3220)})
        self.assertEqual(b.hal.report(), ["ch0 0x40 ina226 ok", "ch1 0x41 no answer",
                                          "ch2 0x42 wrong chip 5449:3220"])
        b2 = Bench(faults={0: ("stuck_low", True)})
        self.assertEqual(b2.hal.report(), ["ch0 0x40 bus held low", "ch1 0x41 bus held low",
                                           "ch2 0x42 bus held low"])
