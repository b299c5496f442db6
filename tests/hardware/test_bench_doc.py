"""The boot lines ``docs/bench.md`` quotes are what the shipped firmware prints: ``boot.py``'s
network bring-up (with a flashed ``wifi.json``) and ``main.py`` of the default revision, booted
unmodified under the real MicroPython with the parts' ``machine`` and ``network`` modules (a
board whose chips all answer), up to the point where it starts serving."""

from __future__ import annotations

import os
import re
import subprocess
from pathlib import Path

from emulator.mpy import find_micropython

ROOT = Path(__file__).resolve().parents[2]

# The parts world wired as the flashed revision's board; boot.up on the world's clock (the
# Wi-Fi join takes 2 s of simulated time); then firmware/main.py as flashed, its asyncio loop
# not entered (asyncio.run closes the coroutine: the servers are another test's business).
SCRIPT = """
from emulator.parts.world import World, install
from emulator.parts.ina226 import Ina226
from emulator.parts import network
from firmware import boards, boot
w = install(World())
w.lan_cable = False
w.wifi = {"robot": ("secret", "10.0.0.7")}
b = boards.load()
s = b["sense"]
for ch in range(b["channels"]):
    w.bus(s["i2c"]["id"]).attach(s["addrs"][ch], Ina226(lambda t: (0.0, 24.0), seed=ch + 1))
w.wire_adc(b["vin"]["adc_pin"], lambda: 24.0 / b["vin"]["divider"])

def sleep_ms(ms):
    w.set_time(w.now_us + ms * 1000)

def ticks_ms():
    return w.now_us // 1000

print(boot.up(network, boot.read_wifi(), sleep_ms, ticks_ms))
import asyncio
def run(coro):
    coro.close()
asyncio.run = run
import firmware.main
"""


def quoted_boot_lines() -> list[str]:
    text = (ROOT / "docs" / "bench.md").read_text()
    blocks = re.findall(r"```text\n(.*?)```", text, re.S)
    boot = [b for b in blocks if b.startswith("network: ")]
    assert len(boot) == 1, "docs/bench.md: one text block starting with 'network: '"
    return boot[0].splitlines()


def test_the_page_quotes_what_the_firmware_prints(tmp_path: Path) -> None:
    (tmp_path / "wifi.json").write_text('{"ssid": "robot", "password": "secret"}')
    (tmp_path / "boot_check.py").write_text(SCRIPT)
    env = dict(os.environ, MICROPYPATH=f"{ROOT}/emulator/parts:{ROOT}:.frozen")
    done = subprocess.run([find_micropython(), "boot_check.py"], cwd=tmp_path, env=env,
                          capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr
    printed = done.stdout.splitlines()
    assert printed[0] == "network: wlan 10.0.0.7 (ssid robot)"
    assert printed[1].startswith("dxboard ") and printed[1].endswith(" rev-a rp2040")
    assert quoted_boot_lines() == printed


def test_the_calibration_arithmetic_is_the_drivers() -> None:
    """The page's CAL figures are what the firmware's INA226 driver writes for the shunt values
    it names (10 mOhm as built, 10.303 mOhm after the example's correction), and the corrected
    reading of its example is the meter's."""
    from firmware.hal.ina226 import calibration

    text = (ROOT / "docs" / "bench.md").read_text()
    assert "0.00512 / (0.00025 x 0.010) = 2048" in text and calibration(10000) == 2048
    assert "10 mOhm x 1.803 / 1.750 = 10.303 mOhm" in text and round(10000 * 1.803 / 1.750) == 10303
    assert "0.00512 / (0.00025 x 0.010303) = 1987" in text and calibration(10303) == 1987
    assert "2048 x 1.750 / 1.803 = 1987" in text and int(2048 * 1.750 / 1.803) == 1987
    assert "`shunt_uohm` in `firmware/boards/rev_a.py` to 10303" in text
    # the board read 1.803 A on 10 mOhm: 1803 mA = 7212 counts of 2.5 uV; over 10.303 mOhm
    raw = 1803 * 10000 // 2500
    assert abs(raw * 2500 // 10303 - 1750) <= 1


def test_the_reference_runs_as_the_page_says(tmp_path: Path) -> None:
    """The file the page copies to a board imports there on its own (no checkout, no
    ``machine`` model) and ``reference_us()`` prints a time in microseconds."""
    (tmp_path / "board_parts.py").write_text(
        (ROOT / "benchmarks" / "board_parts.py").read_text())
    done = subprocess.run([find_micropython(), "-c",
                           "import board_parts; print(board_parts.reference_us())"],
                          cwd=tmp_path, env=dict(os.environ, MICROPYPATH=".:.frozen"),
                          capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr
    assert int(done.stdout.strip()) > 0
    text = (ROOT / "docs" / "bench.md").read_text()
    assert 'exec "import board_parts; print(board_parts.reference_us())"' in text
