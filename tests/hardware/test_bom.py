"""The committed BOMs and parts pages in ``hardware/`` are what ``hardware/bom.py`` makes from
``firmware/boards`` and ``hardware/parts.py`` now, for every revision there is; the limits are
the arithmetic of the parts' ratings (a shunt's power rating from I^2 R at its channel's
limit, a fuse from the continuous current); and a revision naming a part the catalogue lacks
gets one line and exit 2."""

from __future__ import annotations

import csv
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
REVS = sorted("rev-" + p.stem[4:] for p in (ROOT / "firmware" / "boards").glob("rev_*.py"))


def run(*args: str, cwd: Path = ROOT) -> subprocess.CompletedProcess[str]:
    return subprocess.run([sys.executable, str(ROOT / "hardware" / "bom.py"), *args], cwd=cwd,
                          capture_output=True, text=True, timeout=120)


def test_committed_files_are_the_generators_output(tmp_path: Path) -> None:
    done = run(str(tmp_path))
    assert done.returncode == 0, done.stderr
    made = sorted(str(p.relative_to(tmp_path)) for p in tmp_path.rglob("*") if p.is_file())
    assert made == sorted(f"{rev}/{name}" for rev in REVS for name in ("board.md", "bom.csv"))
    for rel in made:
        assert (ROOT / "hardware" / rel).read_text() == (tmp_path / rel).read_text(), rel


def rows(rev: str) -> dict[str, dict[str, str]]:
    with open(ROOT / "hardware" / rev / "bom.csv", newline="") as f:
        return {r["reference"]: r for r in csv.DictReader(f)}


def test_rev_a_parts_follow_from_the_ratings() -> None:
    got = rows("rev-a")
    assert got["U1"]["mpn"] == "SC0918"  # Pico W
    assert got["SEN1-SEN10"]["mpn"] == "INA226AIDGSR"
    assert got["SEN1-SEN10"]["quantity"] == "10"
    # 10 mOhm at the switch's 5 A limit: 0.25 W, twice that wanted: the 0.5 W 2010 part
    assert got["RS1-RS10"]["mpn"] == "WSL2010R0100FEA"
    # 4 A continuous x 1.25 = 5 A fuse per channel; one holder per fuse and one for the input
    assert got["F1-F10"]["mpn"] == "0287005.PXCN"
    assert got["XF0-XF10"]["quantity"] == "11"
    assert got["D1"]["mpn"] == "SMCJ26A"
    assert all(r["manufacturer"] and r["mpn"] for r in got.values())


def test_rev_a_limits_are_stated() -> None:
    text = (ROOT / "hardware" / "rev-a" / "board.md").read_text()
    assert "| input voltage | 7 V to 26 V |" in text
    assert "| input voltage the ADC can read | 0 V to 36.3 V |" in text
    assert "| sense full scale per channel | 8.19 A | 81.92 mV / 10 mOhm |" in text
    assert "| largest rated_ma for which the instant trip can fire | 1667 mA |" in text


def test_a_part_missing_from_the_catalogue_is_one_line(tmp_path: Path) -> None:
    """A copy of the tree whose rev-a senses with a chip ``parts.py`` does not know."""
    for d in ("firmware", "protocol", "hardware"):
        subprocess.run(["cp", "-r", str(ROOT / d), str(tmp_path / d)], check=True)
    rev = tmp_path / "firmware" / "boards" / "rev_a.py"
    rev.write_text(rev.read_text().replace('"chip": "ina226"', '"chip": "ina999"'))
    done = subprocess.run([sys.executable, "hardware/bom.py", str(tmp_path / "out")],
                          cwd=tmp_path, capture_output=True, text=True, timeout=120,
                          env={"PATH": "/usr/bin:/bin"})
    assert done.returncode == 2
    assert done.stderr.count("\n") == 1 and "Traceback" not in done.stderr
    assert "'ina999'" in done.stderr and "add it to SENSE" in done.stderr


@pytest.mark.parametrize("rev", REVS)
def test_every_revision_has_a_bom_and_pins(rev: str) -> None:
    for name in ("bom.csv", "board.md", "pins.md", "pins.csv", "wiring.svg"):
        assert (ROOT / "hardware" / rev / name).is_file(), name
