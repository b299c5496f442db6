"""Board revisions as data (``firmware/boards``): rev A's description builds, through
``firmware.hal.target.build`` (what ``firmware/main.py`` calls), a HAL that drives the parts world:
its enable and status pins, its ten INA226 and its input divider (main.py's old constant read a
24 V input as about 2,381 V).

Runs under pytest and under the real MicroPython.
"""

import unittest

from emulator.parts.ina226 import Ina226
from emulator.parts.world import World, install
from firmware import boards
from firmware.hal.storage import MemStorage
from tests.emulator.parts.test_machine import target_on


def build(board, input_v=24.0, amps=0.5, world=None, storage=None):
    w = world if world is not None else install(World())
    closed = {}
    for ch, pin in enumerate(board["en_pins"]):
        w.wire_output(pin, (lambda c: lambda level: closed.__setitem__(c, level))(ch))
        w.wire_input(board["status_pins"][ch], (lambda c: lambda: closed.get(c, 0))(ch))
    ohm = board["sense"]["shunt_uohm"] / 1e6
    chips = []
    for ch, addr in enumerate(board["sense"]["addrs"]):
        chip = Ina226((lambda c: lambda t: (amps * ohm if closed.get(c) else 0.0, input_v))(ch))
        w.bus(board["sense"]["i2c"]["id"]).attach(addr, chip)
        chips.append(chip)
    w.wire_adc(board["vin"]["adc_pin"], lambda: input_v / board["vin"]["divider"])
    return w, target_on(w).build(board, storage or MemStorage()), closed, chips


class BoardsTest(unittest.TestCase):
    def test_the_default_revision_is_rev_a(self):
        self.assertEqual(boards.load()["name"], "rev-a")
        self.assertEqual(boards.load("rev-a")["channels"], 10)

    def test_an_unknown_revision_is_refused_with_the_known_ones(self):
        with self.assertRaises(ValueError) as cm:
            boards.load("rev-z")
        self.assertIn("rev-a", str(cm.exception))

    def test_the_description_is_consistent(self):
        b = boards.load("rev-a")
        n = b["channels"]
        self.assertEqual(len(b["en_pins"]), n)
        self.assertEqual(len(b["status_pins"]), n)
        self.assertEqual(len(b["sense"]["addrs"]), n)
        pins = list(b["en_pins"]) + list(b["status_pins"]) + [b["vin"]["adc_pin"]]
        pins += [b["sense"]["i2c"]["sda"], b["sense"]["i2c"]["scl"]]
        self.assertEqual(len(set(pins)), len(pins))  # no pin used twice

    def test_rev_a_builds_a_hal_on_its_parts(self):
        w, hal, closed, _chips = build(boards.load("rev-a"))
        self.assertEqual(hal.n_channels, 10)
        hal.set_switch(3, True)
        self.assertEqual(closed.get(3), 1)
        self.assertTrue(hal.read_switch(3))
        self.assertFalse(hal.read_switch(4))
        w.set_time(w.now_us + 20000)
        out = [0] * 10
        hal.read_currents_ma(out)
        self.assertEqual(out, [0, 0, 0, 500, 0, 0, 0, 0, 0, 0])

    def test_the_input_divider(self):
        b = boards.load("rev-a")
        self.assertEqual(boards.mv_per_count_x1000(b["vin"]), 553)  # 3300 mV x 11 / 65535
        _, hal, _, _ = build(b, input_v=24.0)
        mv = sum(hal.read_input_mv() for _ in range(20)) // 20
        self.assertLess(abs(mv - 24000), 240)  # within 1 %: 12 bit, ENOB 8.7

    def test_every_revision_is_listed_and_consistent(self):
        self.assertEqual(boards.known()[:3], ["rev-a", "rev-b", "rev-c"])
        for name in boards.known():
            b = boards.load(name)
            n = b["channels"]
            self.assertEqual(len(b["en_pins"]), n)
            sense = b["sense"]
            if sense["chip"] == "ina3221":
                self.assertEqual(len(sense["inputs"]), n)
                used = [tuple(i) for i in sense["inputs"]]
                self.assertEqual(len(set(used)), n)  # no input measures two channels
                for chip, k in used:
                    self.assertLess(chip, len(sense["addrs"]))
                    self.assertLess(k, 3)
            if sense["chip"] == "profet":  # two channels a part, one IS node, no status pins
                self.assertEqual(2 * len(sense["den_pins"]), n)
                pins = list(b["en_pins"]) + list(sense["den_pins"]) + [sense["dsel_pin"]]
                self.assertEqual(len(set(pins)), len(pins))
                self.assertIn(sense["is_adc_pin"], (26, 27, 28))
                self.assertNotEqual(sense["is_adc_pin"], b["vin"]["adc_pin"])
                self.assertGreaterEqual(sense["r_is_ohm"], 820)  # the data sheet's minimum

    def test_rev_b_says_which_revisions_exist_when_asked_for_another(self):
        with self.assertRaises(ValueError) as cm:
            boards.load("rev-q")
        self.assertIn("rev-b", str(cm.exception))
