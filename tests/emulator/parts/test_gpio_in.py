"""The switches read back at once: on an RP2040 or RP2350 (``board["mcu"]``) the shipped HAL
(``firmware.hal.target``) reads every switch's read-back pin from the SIO's GPIO_IN register,
one ``machine.mem32`` read a tick, instead of one ``Pin.value()`` a pin. Against the pin by
pin reads, on every revision's parts: the same values under every switch pattern and stuck
status outputs, and the machine calls each path makes, in order; the parts' ``mem32`` itself
(the one register it models, every GPIO as ``Pin.value()`` reads it, anything else refused).

Runs under pytest and under the real MicroPython (``micropython tests/mpy_run.py
tests/emulator/parts``).
"""

import unittest
from array import array

from emulator.parts import machine
from emulator.parts.wiring import wire
from emulator.parts.world import World, install
from firmware import boards
from firmware.hal.storage import MemStorage
from tests.emulator.parts.test_machine import target_on


class Parts:
    """A revision on its parts: each enable drives ``closed[ch]``; a status pin reads the
    switch, or ``stuck[ch]`` when that is not None (a switch whose read-back is stuck)."""

    def __init__(self, rev, mcu=None):
        board = dict(boards.load(rev))
        if mcu is not None:
            board["mcu"] = mcu
        self.board = board
        self.n = n = board["channels"]
        self.w = w = install(World())
        self.closed = [False] * n
        self.stuck = [None] * n
        for ch in range(n):
            w.wire_output(board["en_pins"][ch], self._drive_of(ch))
            if board["status_pins"]:
                w.wire_input(board["status_pins"][ch], self._status_of(ch))
        wire(w, board, self)
        w.wire_adc(board["vin"]["adc_pin"], lambda: 24.0 / board["vin"]["divider"])
        self.hal = target_on(w).build(board, MemStorage())

    def _drive_of(self, ch):
        def drive(level):
            self.closed[ch] = bool(level)
        return drive

    def _status_of(self, ch):
        def status():
            s = self.stuck[ch]
            return self.closed[ch] if s is None else s
        return status

    # the electrics wiring.wire asks for: 0.5 A a channel while its switch is closed
    def source(self, ch, ohm):
        return lambda t: ((0.5 if self.closed[ch] else 0.0) * ohm, 24.0)

    def load(self, ch):
        return lambda t: 0.5

    def drive(self, ch, level):
        self.closed[ch] = bool(level)


class Calls:
    """Every ``Pin.value()`` read and ``mem32`` read of the parts' ``machine`` while on, in
    order: ("pin", GPIO) or ("mem32", address)."""

    def __init__(self):
        self.log = []
        self.pin_value = machine.Pin.value
        self.mem_get = type(machine.mem32).__getitem__

    def __enter__(self):
        log, pin_value, mem_get = self.log, self.pin_value, self.mem_get

        def value(pin, x=None):
            if x is None:
                log.append(("pin", pin.id))
            return pin_value(pin, x)

        def getitem(mem, addr):
            log.append(("mem32", addr))
            return mem_get(mem, addr)
        machine.Pin.value = value
        type(machine.mem32).__getitem__ = getitem
        return self

    def __exit__(self, *exc):
        machine.Pin.value = self.pin_value
        type(machine.mem32).__getitem__ = self.mem_get


def script(parts):
    """Switch patterns and stuck read-backs a step each: per step, ``read_switches`` (the
    HAL's tick read), the pin by pin reads (``read_switch``) and the machine calls of the
    first."""
    install(parts.w)  # (machine objects read the world installed last)
    hal, n = parts.hal, parts.n
    got = []
    for step in range(40):
        pattern = (step * 0x2B5 + (step >> 2)) & ((1 << n) - 1)
        if step == 39:
            pattern = (1 << n) - 1
        for ch in range(n):
            hal.set_switch(ch, bool(pattern >> ch & 1))
        for ch in range(n):  # a stuck read-back now and then, high or low
            k = (step + ch) % 7
            parts.stuck[ch] = True if k == 0 else False if k == 3 else None
        out = array("i", [7] * n)
        with Calls() as calls:
            hal.read_switches(out)
        ref = [1 if hal.read_switch(ch) else 0 for ch in range(n)]
        got.append((list(out), ref, calls.log))
    return got


class GpioInTest(unittest.TestCase):
    def check(self, rev):
        parts = Parts(rev)
        hal, board = parts.hal, parts.board
        self.assertEqual(hal.gpio_in, machine.SIO_GPIO_IN)  # rev A-C: an RP2040
        back = board["status_pins"] or board["en_pins"]
        seen = 0
        for out, ref, calls in script(parts):
            self.assertEqual(out, ref)  # the values the pins read one by one
            self.assertEqual(calls, [("mem32", machine.SIO_GPIO_IN)])  # one read, no pin
            seen |= sum(out[ch] << ch for ch in range(parts.n))
        self.assertEqual(seen, (1 << parts.n) - 1)  # every switch read both ways

        # an MCU without GPIO_IN: pin by pin, in channel order, the same values
        pins = Parts(rev, mcu="esp32s3")
        self.assertIsNone(pins.hal.gpio_in)
        want, got = script(parts), script(pins)
        self.assertEqual(len(got), len(want))
        for i in range(len(want)):
            self.assertEqual(got[i][0], want[i][0])
            self.assertEqual(got[i][2], [("pin", p) for p in back])
        return parts

    def test_rev_a(self):
        parts = self.check("rev-a")
        # a stuck read-back is what GPIO_IN says, not the enable: the switch reads as stuck
        install(parts.w)
        parts.hal.set_switch(0, False)
        parts.stuck[0] = True
        out = array("i", [0] * parts.n)
        parts.hal.read_switches(out)
        self.assertEqual(out[0], 1)

    def test_rev_b(self):
        self.check("rev-b")

    def test_rev_c_reads_its_enables_back(self):
        self.check("rev-c")

    def test_the_rp2350_has_it_too(self):
        self.assertEqual(Parts("rev-a", mcu="rp2350").hal.gpio_in, machine.SIO_GPIO_IN)


class Mem32Test(unittest.TestCase):
    def test_every_gpio_as_pin_value_reads_it_and_nothing_else(self):
        w = install(World())
        w.wire_input(5, lambda: True)
        w.wire_input(6, lambda: False)
        out = machine.Pin(2, machine.Pin.OUT, value=1)
        machine.Pin(3, machine.Pin.OUT, value=0)
        machine.Pin(5, machine.Pin.IN)
        machine.Pin(6, machine.Pin.IN, machine.Pin.PULL_UP)  # its net wins over the pull
        up = machine.Pin(7, machine.Pin.IN, machine.Pin.PULL_UP)  # nothing wired: the pull
        machine.Pin(8, machine.Pin.IN, machine.Pin.PULL_DOWN)
        word = machine.mem32[machine.SIO_GPIO_IN]
        self.assertEqual(word, 1 << 2 | 1 << 5 | 1 << 7)  # GPIO 9 never set up: 0
        for gpio in range(30):
            self.assertEqual(word >> gpio & 1,
                             machine.Pin(gpio).value() if gpio in (5, 6, 8) else
                             (out.value() if gpio == 2 else up.value() if gpio == 7 else
                              0))
        out.value(0)
        self.assertEqual(machine.mem32[machine.SIO_GPIO_IN] >> 2 & 1, 0)
        for addr in (0xD0000000, 0xD0000008, 0x40014000, 0):
            with self.assertRaises(ValueError):
                machine.mem32[addr]
        with self.assertRaises(ValueError):
            machine.mem32[machine.SIO_GPIO_IN] = 1

    def test_a_reboot_puts_every_pad_back(self):
        w = install(World())
        machine.Pin(7, machine.Pin.IN, machine.Pin.PULL_UP)
        self.assertEqual(machine.mem32[machine.SIO_GPIO_IN], 1 << 7)
        w.reboot()
        self.assertEqual(machine.mem32[machine.SIO_GPIO_IN], 0)


if __name__ == "__main__":
    unittest.main()
