"""Why the board booted, on the rp2 port's real semantics: ``machine.reset()`` goes through the
RP2040's watchdog, so the next boot reads ``WDT_RESET`` for a reboot the host asked for. The
board must not count that as a watchdog reset (three in a row put it in safe mode): the HAL
marks a requested reboot in storage and reads it back as ``RESET_SOFT``.

Runs under pytest and under the real MicroPython.
"""

import unittest

from emulator.parts.world import BoardReset, World, install
from firmware import boards
from firmware.hal.storage import MemStorage
from protocol.constants import RESET_POWER_ON, RESET_SOFT, RESET_WATCHDOG
from tests.emulator.parts.test_boards import build


class ResetCauseTest(unittest.TestCase):
    def boot(self, w, storage):
        return build(boards.load("rev-a"), world=w, storage=storage)[1]

    def test_power_on(self):
        hal = build(boards.load("rev-a"))[1]
        self.assertEqual(hal.reset_cause(), RESET_POWER_ON)

    def test_a_requested_reboot_is_soft_not_watchdog(self):
        w = install(World())
        storage = MemStorage()
        hal = self.boot(w, storage)
        self.assertRaises(BoardReset, hal.reboot)
        w.reboot()
        self.assertEqual(self.boot(w, storage).reset_cause(), RESET_SOFT)
        # and the mark is used once: a later watchdog reset is a watchdog reset
        hal = self.boot(w, storage)
        w.set_time(w.now_us + 1000)
        with self.assertRaises(BoardReset):
            w.set_time(w.now_us + 3000000)  # nobody feeds it
        w.reboot()
        self.assertEqual(self.boot(w, storage).reset_cause(), RESET_WATCHDOG)
