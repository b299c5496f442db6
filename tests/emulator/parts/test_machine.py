"""The ``machine`` module of the parts world: the rp2 port's API with real semantics.

Runs under pytest and under the real MicroPython (``micropython tests/mpy_run.py
tests/emulator/parts``); ``test_import_by_name`` boots a separate ``micropython`` with
``emulator/parts`` on ``MICROPYPATH`` as the firmware's tests do.
"""

import errno
import sys
import unittest

from emulator.parts import ina226 as I
from emulator.parts import machine
from emulator.parts.boardtime import BoardTime
from emulator.parts.ina226 import Ina226
from emulator.parts.world import BoardReset, World, install


def world_with_chip(shunt_v=0.020, bus_v=24.0):
    w = install(World())
    chip = Ina226(lambda t: (shunt_v, bus_v))
    w.bus(0).attach(0x40, chip)
    return w, chip


class PinTest(unittest.TestCase):
    def test_an_output_drives_its_net_and_an_input_reads_its_own(self):
        w = install(World())
        seen = []
        w.wire_output(2, seen.append)
        w.wire_input(12, lambda: len(seen) > 1 and seen[-1])
        en = machine.Pin(2, machine.Pin.OUT, value=0)
        st = machine.Pin(12, machine.Pin.IN)
        self.assertEqual(seen, [0])
        self.assertEqual(st.value(), 0)
        en.value(1)
        self.assertEqual(seen, [0, 1])
        self.assertEqual(en.value(), 1)  # an output reads its latch back
        self.assertEqual(st.value(), 1)
        en.off()
        self.assertEqual(st(), 0)
        en.toggle()
        self.assertEqual(seen[-1], 1)

    def test_an_unwired_input_reads_its_pull(self):
        install(World())
        self.assertEqual(machine.Pin(5, machine.Pin.IN, machine.Pin.PULL_UP).value(), 1)
        self.assertEqual(machine.Pin(6, machine.Pin.IN, machine.Pin.PULL_DOWN).value(), 0)

    def test_a_pin_that_does_not_exist(self):
        install(World())
        self.assertRaises(ValueError, machine.Pin, 30)


class I2CTest(unittest.TestCase):
    def test_scan_finds_the_chips_that_acknowledge(self):
        w, chip = world_with_chip()
        w.bus(0).attach(0x45, Ina226())
        i2c = machine.I2C(0, freq=400000)
        self.assertEqual(i2c.scan(), [0x40, 0x45])
        chip.inject("nack")
        self.assertEqual(i2c.scan(), [0x45])

    def test_register_reads_and_writes(self):
        world_with_chip()
        i2c = machine.I2C(0, freq=400000)
        self.assertEqual(i2c.readfrom_mem(0x40, 0xFF, 2), b"\x22\x60")
        buf = bytearray(2)
        i2c.readfrom_mem_into(0x40, 0xFE, buf)
        self.assertEqual(bytes(buf), b"\x54\x49")
        i2c.writeto_mem(0x40, I.CALIBRATION, b"\x0a\x00")
        self.assertEqual(i2c.readfrom_mem(0x40, I.CALIBRATION, 2), b"\x0a\x00")
        i2c.writeto(0x40, b"\xff")  # pointer only, then a plain read
        self.assertEqual(i2c.readfrom(0x40, 2), b"\x22\x60")

    def test_a_register_read_takes_its_bits_at_the_bus_frequency(self):
        # START, address+W, pointer, repeated START, address+R, 2 data bytes, STOP: 48 bits
        w, _ = world_with_chip()
        fast = machine.I2C(0, freq=400000)
        t = w.now_us
        fast.readfrom_mem(0x40, I.SHUNT, 2)
        self.assertEqual(w.now_us - t, 120)  # 48 / 400 kHz
        slow = machine.I2C(0, freq=100000)
        t = w.now_us
        slow.readfrom_mem(0x40, I.SHUNT, 2)
        self.assertEqual(w.now_us - t, 480)

    def test_the_chip_sees_the_simulated_clock(self):
        w, _ = world_with_chip(0.020)
        i2c = machine.I2C(0)
        self.assertEqual(i2c.readfrom_mem(0x40, I.SHUNT, 2), b"\x00\x00")
        w.set_time(2200)
        self.assertEqual(i2c.readfrom_mem(0x40, I.SHUNT, 2), b"\x1f\x40")  # 8000: 20 mV

    def test_an_absent_or_nacking_address_is_enodev(self):
        w, chip = world_with_chip()
        i2c = machine.I2C(0)
        with self.assertRaises(OSError) as cm:
            i2c.readfrom_mem(0x41, 0, 2)
        self.assertEqual(cm.exception.args[0], errno.ENODEV)
        chip.inject("nack")
        t = w.now_us
        with self.assertRaises(OSError) as cm:
            i2c.readfrom_mem_into(0x40, 0, bytearray(2))
        self.assertEqual(cm.exception.args[0], errno.ENODEV)
        self.assertEqual(w.now_us - t, 28)  # 11 bits: the address, no ACK, STOP

    def test_a_bus_held_low_times_out(self):
        w, chip = world_with_chip()
        w.bus(0).attach(0x41, Ina226())
        chip.inject("stuck_low")
        i2c = machine.I2C(0, timeout=50000)
        t = w.now_us
        with self.assertRaises(OSError) as cm:
            i2c.readfrom_mem(0x41, 0xFF, 2)  # another chip: the whole bus is down
        self.assertEqual(cm.exception.args[0], errno.ETIMEDOUT)
        self.assertEqual(w.now_us - t, 50000)
        self.assertRaises(OSError, i2c.scan)

    def test_only_two_controllers(self):
        install(World())
        self.assertRaises(ValueError, machine.I2C, 2)


class AdcTest(unittest.TestCase):
    def test_twelve_bits_scaled_to_sixteen_with_the_rp2040s_noise(self):
        w = install(World(seed=7))
        w.wire_adc(26, lambda: 1.65)
        adc = machine.ADC(machine.Pin(26))
        raws = []
        for _ in range(2000):
            v = adc.read_u16()
            raw = v >> 4
            self.assertEqual(v & 0xF, raw >> 8)  # the port's scaling: raw << 4 | raw >> 8
            raws.append(raw)
        mean = sum(raws) / len(raws)
        rms = (sum((r - mean) ** 2 for r in raws) / len(raws)) ** 0.5
        self.assertLess(abs(mean - 2047.5), 0.5)
        self.assertGreater(rms, 2.4)  # ENOB about 8.7: 2.84 LSB rms
        self.assertLess(rms, 3.3)

    def test_the_rails_clamp(self):
        w = install(World())
        w.wire_adc(27, lambda: 5.0)
        w.wire_adc(28, lambda: -1.0)
        self.assertEqual(machine.ADC(1).read_u16(), 65535)
        self.assertEqual(machine.ADC(machine.Pin(28)).read_u16(), 0)

    def test_a_pin_without_adc(self):
        install(World())
        self.assertRaises(ValueError, machine.ADC, machine.Pin(2))


class ResetTest(unittest.TestCase):
    def test_power_on(self):
        install(World())
        self.assertEqual(machine.reset_cause(), machine.PWRON_RESET)
        self.assertEqual(machine.PWRON_RESET, 1)
        self.assertEqual(machine.WDT_RESET, 3)
        self.assertEqual(len(machine.unique_id()), 8)

    def test_a_fed_watchdog_keeps_the_board_running(self):
        w = install(World())
        wdt = machine.WDT(timeout=2000)
        for k in range(1, 20):
            w.set_time(k * 1000000)
            wdt.feed()

    def test_an_unfed_watchdog_resets_the_board(self):
        w = install(World())
        seen = []
        w.wire_output(2, seen.append)
        machine.Pin(2, machine.Pin.OUT, value=1)
        machine.WDT(timeout=2000)
        w.set_time(2000000)  # exactly the timeout: still alive
        with self.assertRaises(BoardReset):
            w.set_time(2000001)
        with self.assertRaises(BoardReset):
            machine.Pin(3, machine.Pin.OUT)  # nothing runs until the board comes back
        self.assertEqual(w.reboot(), machine.WDT_RESET)
        self.assertEqual(seen[-1], 0)  # the enable line fell with the reset
        self.assertEqual(machine.reset_cause(), machine.WDT_RESET)
        w.set_time(60000000)  # the watchdog is stopped after a reset

    def test_machine_reset_goes_through_the_watchdog_on_rp2(self):
        w = install(World())
        self.assertRaises(BoardReset, machine.reset)
        w.reboot()
        self.assertEqual(machine.reset_cause(), machine.WDT_RESET)

    def test_the_rp2040_watchdog_has_a_maximum(self):
        install(World())
        self.assertRaises(ValueError, machine.WDT, 0, 8389)


class UartTest(unittest.TestCase):
    def test_bytes_both_ways_and_time_on_the_line(self):
        w = install(World())
        u = machine.UART(1, 115200)
        self.assertIsNone(u.read())
        t = w.now_us
        self.assertEqual(u.write(b"hello"), 5)
        self.assertEqual(w.now_us - t, 434)  # 50 bits at 115200 baud
        self.assertEqual(bytes(w.uart_tx[1]), b"hello")
        w.uart_rx[1].extend(b"ab\ncd")
        self.assertEqual(u.any(), 5)
        self.assertEqual(u.readline(), b"ab\n")
        buf = bytearray(4)
        self.assertEqual(u.readinto(buf), 2)
        self.assertEqual(bytes(buf[:2]), b"cd")


def target_on(w):
    """``firmware.hal.target`` imported with this ``machine``, as ``firmware/main.py`` gets it
    on a board, its ``time`` the port's ticks (on CPython, which has none, the world ``w``'s)
    and a ``sleep_us`` charged to ``w``'s clock (``emulator.parts.boardtime``)."""
    sys.modules["machine"] = machine
    try:
        from firmware.hal import target
    finally:
        del sys.modules["machine"]
    port = target._port_time  # the interpreter's own, whatever a test before handed it
    target.time = BoardTime(w, port)
    return target


class TargetHalTest(unittest.TestCase):
    """The shipped HAL (``firmware/hal/target.py``) on this ``machine``: its INA226 path."""

    def hal(self, w):
        target = target_on(w)
        return target.TargetHal((2, 3), (12, 13), i2c=machine.I2C(0),
                                ina226_addrs=(0x40, 0x41), shunt_uohm=10000)

    def test_reads_current_from_the_chips_shunt_register(self):
        w = install(World())
        w.bus(0).attach(0x40, Ina226(lambda t: (0.020, 24.0)))  # 2 A across 10 mOhm
        w.bus(0).attach(0x41, Ina226(lambda t: (0.0005, 24.0)))  # 50 mA
        hal = self.hal(w)
        w.set_time(10000)  # configured for the tick at boot: a result every 8.8 ms
        out = [0, 0]
        hal.read_currents_ma(out)
        self.assertEqual(out, [2000, 50])
