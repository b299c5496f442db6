"""Rev B as flashed: its description (``firmware/boards/rev_b.py``) builds, through
``firmware.hal.target.build`` (what ``firmware/main.py`` calls), the INA3221 driver on four
INA3221 models of the parts world; what the driver reads, and what the board
(``firmware.board.Board`` on that HAL) answers to each part fault and to the fast trip input.

Runs under pytest and under the real MicroPython (``micropython tests/mpy_run.py
tests/emulator/parts``).
"""

import errno
import unittest

from emulator.parts import ina3221 as T
from emulator.parts.wiring import wire
from emulator.parts.world import World, install
from firmware import boards
from firmware.hal import TRIPPED
from firmware.hal.chipbank import ChipBank
from firmware.hal.ina3221 import limit_code
from firmware.hal.storage import MemStorage
from protocol.constants import EV_FAULT, EV_TRIP, F_SENSOR, F_SHORT, F_STUCK_ON, ST_ON
from tests.emulator.parts.test_machine import target_on
from tests.emulator.parts.test_target_ina226 import BoardBench

RATED_MA = 3000  # trip at 3 x rated (9 A), inrush up to 4 x rated (12 A)


class Bench(BoardBench):
    """Rev B: ten switches, each load through a shunt into an INA3221 input."""

    def __init__(self, load_a=None, faults=None):
        self.b = b = boards.load("rev-b")
        self.n = n = b["channels"]
        self.w = w = install(World())
        self.load_a = list(load_a or [0.1 * (ch + 1) for ch in range(n)])
        self.spike = [None] * n  # fn(t_us) -> amps, instead of load_a
        self.welded = set()  # channels whose switch conducts whatever its enable says
        self.closed = [False] * n
        for ch in range(n):
            w.wire_output(b["en_pins"][ch], self._switch(ch))
            w.wire_input(b["status_pins"][ch], self._status(ch))
        self.chips = []
        for chip, _k in wire(w, b, self):
            if chip not in self.chips:
                self.chips.append(chip)
        for i, (fault, value) in (faults or {}).items():  # already there at power-on
            self.chips[i].inject(fault, value)
        w.wire_adc(b["vin"]["adc_pin"], lambda: 24.0 / 11)
        self.hal = target_on(w).build(b, MemStorage())
        self.board = None
        self.cursor = 0

    def source(self, ch, ohm):
        def source(t_us):
            if not self.closed[ch] and ch not in self.welded:
                return 0.0, 0.0
            fn = self.spike[ch]
            amps = fn(t_us) if fn is not None else self.load_a[ch]
            return amps * ohm, 24.0
        return source


class DriverTest(unittest.TestCase):
    def test_boot_checks_ids_and_configures_for_the_tick(self):
        b = Bench()
        self.assertEqual([c.regs[T.CONFIG] for c in b.chips], [0x721F, 0x721F, 0x621F, 0x621F])
        self.assertEqual(T.cycle_us(0x721F), 8736)  # 3 x (140 + 588) x 4 < 10 ms
        self.assertEqual(T.cycle_us(0x621F), 5824)
        for c in b.chips:
            self.assertTrue(c.regs[T.MASK_ENABLE] & T.CEN)
        self.assertEqual(b.hal.report()[:4], ["ch0 0x40.0 ina3221 ok", "ch1 0x40.1 ina3221 ok",
                                              "ch2 0x40.2 ina3221 ok", "ch3 0x41.0 ina3221 ok"])

    def test_a_fresh_sample_every_tick(self):
        b = Bench()
        b.boot()
        self.assertEqual([c.current_ma for c in b.board.channels],
                         [100 * (ch + 1) for ch in range(10)])
        before = b.chips[3].conversions
        b.load_a[9] = 2.0
        b.run(20)
        self.assertEqual(b.board.channels[9].current_ma, 2000)
        self.assertGreaterEqual(b.chips[3].conversions - before, 2)

    def test_bus_time_per_tick(self):
        b = Bench()
        b.boot()
        bus = b.w.bus(0)
        t = bus.busy_us
        b.run(10)
        self.assertEqual(bus.busy_us - t, 15 * 120)  # 10 shunts, 4 MASK/ENABLE, 1 CONFIG

    def test_critical_limit_is_the_channels_trip_current(self):
        b = Bench()
        b.boot()
        self.assertEqual(b.board.channels[4].state, ST_ON)
        want = limit_code(RATED_MA * 3, 10000)
        self.assertEqual(want, 2250 << 3)  # 9 A x 10 mOhm = 90 mV = 2250 x 40 uV
        self.assertEqual(b.chips[1].regs[T.critical_reg(1)], want)
        b.board.switch(4, False)
        b.board.switch(4, True)  # in INRUSH the limit is the inrush limit, 12 A
        self.assertEqual(b.chips[1].regs[T.critical_reg(1)], limit_code(RATED_MA * 4, 10000))


class FastTripTest(unittest.TestCase):
    def test_a_spike_the_average_hides_trips_the_channel(self):
        b = Bench()
        b.boot()
        b.events()
        # 20 A during one millisecond in ten, 1 A otherwise: each averaged result stays well
        # under the 9 A trip, but a shunt conversion now and then sees the spike
        b.spike[0] = lambda t: 20.0 if t % 10000 < 1000 else 1.0
        b.run(200)
        ch = b.board.channels[0]
        trips = [e for e in b.events() if e[1] == EV_TRIP and e[2] == 0]
        self.assertTrue(trips)
        self.assertEqual(trips[0][5], F_SHORT)
        self.assertEqual(trips[0][6], RATED_MA * 3)  # the limit, not a made-up current
        self.assertNotEqual(ch.state, ST_ON)
        self.assertFalse(b.closed[0])
        self.assertGreater(b.hal.ina.trips, 0)
        self.assertEqual(b.board.channels[1].state, ST_ON)

    def test_a_switch_stuck_on_into_a_short_is_seen_through_the_flag(self):
        b = Bench()
        b.boot()
        b.board.switch(2, False)
        b.run(100)
        b.welded.add(2)
        b.closed[2] = True  # its status pin reads it on: the switch conducts
        b.spike[2] = lambda t: 30.0  # over the shunt's 16.38 A full scale: CRITICAL every time
        b.run(3000)
        ch = b.board.channels[2]
        self.assertTrue(ch.live & F_STUCK_ON)

    def test_without_the_critical_flag_the_average_alone_would_not_trip(self):
        b = Bench()
        b.boot()
        b.spike[0] = lambda t: 20.0 if t % 10000 < 1000 else 1.0
        seen = []
        for _ in range(20):
            b.w.set_time(b.w.now_us + 10000)
            b.chips[0].advance(b.w.now_us)
            seen.append(T.shunt_code(b.chips[0].regs[T.shunt_reg(0)]) * 4)  # mA
        self.assertLess(max(seen), RATED_MA * 3)


class PartFaultTest(unittest.TestCase):
    def test_nack_is_a_sensor_fault_of_its_three_channels(self):
        b = Bench()
        b.boot(protected=(3,))
        b.events()
        b.chips[1].inject("nack")
        b.run(5000)
        for i in (3, 4, 5):
            ch = b.board.channels[i]
            self.assertEqual(ch.state, ST_ON)
            self.assertTrue(b.closed[i])
            self.assertTrue(ch.live & F_SENSOR)
        self.assertEqual(b.board.channels[6].current_ma, 700)
        b.chips[1].clear()
        b.run(100)
        self.assertFalse(b.board.channels[3].live & F_SENSOR)
        self.assertEqual(b.board.channels[4].current_ma, 500)
        said = [e[5] for e in b.events() if e[1] == EV_FAULT and e[2] == 3]
        self.assertEqual(said, [F_SENSOR, 0])

    def test_a_bus_held_low_blinds_every_channel_and_keeps_them_on(self):
        b = Bench()
        b.boot()
        b.chips[3].inject("stuck_low")
        b.run(1000)
        for ch in b.board.channels:
            self.assertTrue(ch.live & F_SENSOR)
            self.assertEqual(ch.state, ST_ON)
        b.chips[3].clear()
        b.run(300)
        self.assertEqual(b.board.channels[9].current_ma, 1000)
        self.assertFalse(b.board.channels[0].live & F_SENSOR)

    def test_a_chip_reset_is_noticed_and_configured_again_limits_included(self):
        b = Bench()
        b.boot()
        b.chips[2].inject("reset", now_us=b.w.now_us)
        self.assertEqual(b.chips[2].regs[T.critical_reg(0)], 0x7FF8)
        b.run(100)  # four chips checked in turn
        self.assertEqual(b.chips[2].regs[T.CONFIG], 0x621F)
        self.assertEqual(b.chips[2].regs[T.critical_reg(0)], limit_code(RATED_MA * 3, 10000))
        self.assertTrue(b.chips[2].regs[T.MASK_ENABLE] & T.CEN)
        self.assertEqual(b.hal.ina.resets, 1)
        self.assertEqual(b.board.channels[6].current_ma, 700)

    def test_a_wrong_chip_is_never_trusted(self):
        b = Bench(faults={0: ("die_id", 0x2260)})  # an INA226 where an INA3221 belongs
        b.boot()
        for i in (0, 1, 2):
            self.assertTrue(b.board.channels[i].live & F_SENSOR)
            self.assertEqual(b.board.channels[i].state, ST_ON)
        self.assertEqual(b.chips[0].regs[T.CONFIG], 0x7127)  # never written to
        self.assertEqual(b.hal.report()[0], "ch0 0x40.0 wrong chip 5449:2260")
        self.assertEqual(b.board.channels[3].current_ma, 400)

    def test_stuck_gain_and_open_shunt(self):
        b = Bench()
        b.boot()
        b.chips[0].inject("stuck")
        b.load_a[0] = 2.5
        b.run(100)
        self.assertEqual(b.board.channels[0].current_ma, 100)  # frozen: the board cannot tell
        b.chips[1].inject("gain", 1.5)
        b.run(100)
        self.assertLessEqual(abs(b.board.channels[4].current_ma - 750), 4)  # 4 mA a count
        b.chips[3].inject("open_shunt")
        b.run(100)
        self.assertEqual(b.board.channels[8].current_ma, 0)


# per tick, (transaction of the tick that fails, how): a NACK at every place of a tick's
# transactions (MASK/ENABLE, SHUNT, CONFIG check, a configuration after), the bus held low at
# a few; ("nack", chip), ("reset", chip), ("clear", chip): a chip's own fault from that tick on
SCRIPT = ([None] * 4 + [(k, "nack") for k in range(24)] + [None] * 3
          + [(0, "stuck_low")] + [None] * 12 + [(1, "stuck_low")] + [None] * 12
          + [(5, "stuck_low")] + [None] * 12 + [(14, "stuck_low")] + [None] * 12
          + [("nack", 1)] + [None] * 3 + [("clear", 1)] + [None] * 2 + [("reset", 2)]
          + [(4, "nack")] + [("reset", 0)] + [(0, "nack")] + [("nack", 3)] + [(2, "nack")]
          + [("clear", 3)] + [None] * 8)


def read_script(python):
    """Rev B's driver through ``SCRIPT``, the CRITICAL flags firing on three channels now and
    then: every I2C transaction in order (address, register and the word read or written, or
    minus the error: one int each, to fit MicroPython's heap) and per tick what it read and
    holds. ``python``: by ``ChipBank.read`` (the
    reference, Python only), else by the driver's own read (``firmware.fast.ina3221_read``)."""
    b = Bench()
    bank = b.hal.ina
    if python:
        bank.read = lambda out: ChipBank.read(bank, out)
        b.hal.read_currents_ma = bank.read  # the HAL binds its bank's read when built
    b.closed = [True] * b.n
    for ch in range(b.n):
        bank.set_trip_ma(ch, RATED_MA * 3)
    # over the limit during every third 10 ms, on inputs of three chips (first, middle, last)
    for ch in (0, 4, 9):
        b.spike[ch] = lambda t, ch=ch: 20.0 if (t // 10000 + ch) % 3 == 0 else 0.5
    devices = b.w.bus(0).devices
    i2c = bank.i2c
    log = []
    at = [0, -1, ""]  # the tick's transactions so far; the one to fail, how

    def fault(addr):
        if at[0] == at[1]:
            dev = devices[addr] if at[2] == "nack" else devices[0x40]
            setattr(dev, at[2], True)
            return dev
        return None

    def logged(real):
        def call(addr, reg, buf):
            dev = fault(addr)
            at[0] += 1
            try:
                real(addr, reg, buf)
                log.append((addr * 256 + reg) * 65536 + buf[0] * 256 + buf[1])
            except OSError as exc:
                log.append(-((addr * 256 + reg) * 65536 + exc.args[0]))
                raise
            finally:
                if dev is not None:
                    setattr(dev, at[2], False)
        return call

    i2c.readfrom_mem_into = logged(i2c.readfrom_mem_into)
    bank.rd = i2c.readfrom_mem_into  # the bank binds the bus's read when built
    i2c.writeto_mem = logged(i2c.writeto_mem)
    out = [0] * b.n
    seen = []
    for step in SCRIPT:
        b.w.set_time(b.w.now_us + 10000 - b.w.now_us % 10000)
        at[0], at[1] = 0, -1
        if step is not None and isinstance(step[0], int):
            at[1], at[2] = step
        elif step is not None:
            chip = b.chips[step[1]]
            if step[0] == "clear":
                chip.clear()
            else:
                chip.inject(step[0], now_us=b.w.now_us)
        b.hal.read_currents_ma(out)
        seen.append((list(out), list(bank.state), list(bank.flags), bank.trips, bank.errors,
                     bank.resets, bank.bus_wait, bank.prog[3]))
    return log, seen


class ReadPathTest(unittest.TestCase):
    """The driver's read (``Ina3221Bank.read``: ``firmware.fast.ina3221_read``, Python for a
    chip not ready) against ``ChipBank.read``, the same parts and faults: the same bus
    transactions in the same order, the same values and codes, the same state after each
    tick."""

    def test_the_read_is_chipbank_reads_transaction_for_transaction(self):
        ref_log, ref = read_script(True)
        log, got = read_script(False)
        for i in range(len(SCRIPT)):
            self.assertEqual(got[i], ref[i], f"tick {i} ({SCRIPT[i]!r})")
        self.assertEqual(len(log), len(ref_log))
        for i in range(len(ref_log)):
            self.assertEqual(log[i], ref_log[i], f"transaction {i}")
        # the script reaches what it is for: flags, NACKs, a bus held low, resets
        self.assertTrue(any(TRIPPED in o[0] for o in ref))
        self.assertGreater(ref[-1][3], 5)  # trips
        self.assertTrue(any(e < 0 and -e % 65536 == errno.ENODEV for e in ref_log))
        self.assertTrue(any(e < 0 and -e % 65536 == errno.ETIMEDOUT for e in ref_log))
        self.assertTrue(any(o[6] for o in ref))  # the bus waited
        self.assertEqual(ref[-1][5], 2)  # both resets noticed
        self.assertEqual(ref[-1][1], [1, 1, 1, 1])  # every chip back

    def test_a_critical_flag_reads_tripped_once_then_the_current(self):
        b = Bench()
        bank = b.hal.ina
        b.closed = [True] * b.n
        for ch in range(b.n):
            bank.set_trip_ma(ch, RATED_MA * 3)
        b.spike[4] = lambda t: 20.0  # chip 1, input 1: over its limit every conversion
        out = [0] * b.n
        b.w.set_time(b.w.now_us + 10000)
        b.hal.read_currents_ma(out)
        self.assertEqual(out[4], TRIPPED)
        self.assertEqual(out[3], 400)  # the chip's other inputs read on
        self.assertEqual(out[5], 600)
        self.assertEqual(bank.trips, 1)
        self.assertFalse(bank.flags[1] & (T.CF1 >> 1))  # cleared once told
        b.spike[4] = None
        b.load_a[4] = 0.5
        for _ in range(2):  # the flag latched until MASK/ENABLE is read, then a clean cycle
            b.w.set_time(b.w.now_us + 10000)
            b.hal.read_currents_ma(out)
        self.assertEqual(out[4], 500)
        self.assertEqual(bank.trips, 1)
