# cpython-only: starts the micropython binary as a subprocess
"""``import machine`` in a real ``micropython`` with ``emulator/parts`` on ``MICROPYPATH`` gets the
parts world's module (not the unix port's built-in one), and the shipped ``firmware/hal/target.py``
reads an INA226 model through it on MicroPython's own ``time``."""

import os
import subprocess
import unittest
from pathlib import Path

from emulator.mpy import find_micropython

ROOT = Path(__file__).resolve().parents[3]

SCRIPT = """
from emulator.parts.world import World, install
from emulator.parts.ina226 import Ina226
w = install(World())
w.bus(0).attach(0x40, Ina226(lambda t: (0.020, 24.0)))
import machine
from firmware.hal.target import TargetHal
hal = TargetHal((2,), (12,), i2c=machine.I2C(0), ina226_addrs=(0x40,), shunt_uohm=10000)
w.set_time(10000)
print(machine.__file__, machine.reset_cause(), hal.read_current_ma(0))
"""


class ImportByNameTest(unittest.TestCase):
    def test_import_by_name(self):
        env = dict(os.environ, MICROPYPATH="emulator/parts:.:.frozen")
        out = subprocess.run([find_micropython(), "-c", SCRIPT], cwd=ROOT, env=env,
                             capture_output=True, text=True, timeout=120, check=True).stdout
        self.assertEqual(out.split(), ["emulator/parts/machine.py", "1", "2000"])

    def test_boot_on_the_unix_port(self):
        env = dict(os.environ, MICROPYPATH=".:.frozen")  # no parts: the port's own modules
        out = subprocess.run([find_micropython(), "-c", "from firmware import boot; boot.run()"],
                             cwd=ROOT, env=env, capture_output=True, text=True, timeout=120,
                             check=True).stdout
        self.assertEqual(out.strip(),
                         "network: none (no network module: the host's sockets stand in)")
