"""The parts benchmark (``benchmarks/board_parts.py``) measures every revision in
``firmware/boards`` on its own part models, wired by ``emulator.parts.wiring``: the shipped
HAL and protection boot under MicroPython, every channel comes on, and the sensing time per
tick is the I2C bus's (rev A, rev B) or the ADC's conversions and settling (rev C)."""

from __future__ import annotations

import os
import subprocess
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
MICROPYTHON = ROOT / ".venv" / "bin" / "micropython"
REVS = sorted("rev-" + p.stem[4:] for p in (ROOT / "firmware" / "boards").glob("rev_*.py"))


def parts_line(rev: str) -> list[str]:
    env = dict(os.environ, MICROPYPATH="emulator/parts:.:.frozen", DXBOARD_PARTS_TICKS="20")
    done = subprocess.run([str(MICROPYTHON), "benchmarks/board_parts.py", rev], cwd=ROOT,
                          env=env, capture_output=True, text=True, timeout=600)
    lines = [ln for ln in done.stdout.splitlines() if ln.startswith("PARTS")]
    assert done.returncode == 0 and lines, done.stderr + done.stdout
    return lines[0].split()


@pytest.mark.parametrize("rev", REVS)
def test_every_revision_is_measured_on_its_parts(rev: str) -> None:
    fields = parts_line(rev)
    assert fields[1] == rev and fields[2] != "none", fields
    n, on, *_, bus_mean, bus_max, heap, _own = (int(x) for x in fields[2:])
    assert on == n == 10
    assert 0 < bus_mean <= bus_max < 10000  # some sensing time, within the 10 ms tick
    assert heap > 0


def test_rev_c_senses_through_the_adc() -> None:
    """Rev C has no I2C: each of its 10 channels waits t_sIS (20 us, one ``sleep_us`` charged to
    the simulated clock) and takes two conversions averaged, 2 us each on the RP2040's ADC:
    240 us, plus the input voltage's conversion."""
    bus_mean = int(parts_line("rev-c")[-4])
    assert 240 <= bus_mean < 1000
