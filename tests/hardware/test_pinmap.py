"""The committed pin maps and wiring pictures in ``hardware/`` are what ``hardware/pinmap.py``
makes from ``firmware/boards`` now (they cannot drift from what the firmware boots), and the
command the docs show works."""

from __future__ import annotations

import subprocess
import sys
import xml.etree.ElementTree as ET
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]


def test_committed_files_are_the_generators_output(tmp_path: Path) -> None:
    done = subprocess.run([sys.executable, "hardware/pinmap.py", str(tmp_path)], cwd=ROOT,
                          capture_output=True, text=True, timeout=120)
    assert done.returncode == 0, done.stderr
    made = sorted(p.relative_to(tmp_path) for p in tmp_path.rglob("*") if p.is_file())
    revs = sorted("rev-" + p.stem[4:] for p in (ROOT / "firmware" / "boards").glob("rev_*.py"))
    assert [str(p) for p in made] == [f"{rev}/{name}" for rev in revs
                                      for name in ("pins.csv", "pins.md", "wiring.svg")]
    for rel in made:
        assert (ROOT / "hardware" / rel).read_text() == (tmp_path / rel).read_text(), rel


def test_the_pin_map_says_what_the_firmware_uses() -> None:
    text = (ROOT / "hardware" / "rev-a" / "pins.csv").read_text().splitlines()
    assert text[0] == "gpio,function,connects_to"
    rows = [line.split(",") for line in text[1:]]
    assert [r[0] for r in rows] == sorted((r[0] for r in rows), key=int)
    assert ["2", "switch enable", "channel 0 high-side switch IN"] in rows
    assert ["21", "switch status", "channel 9 output read-back"] in rows
    assert ["26", "ADC", "input voltage through a 1:11 divider"] in rows
    ET.fromstring((ROOT / "hardware" / "rev-a" / "wiring.svg").read_text())  # well-formed


def test_the_drawings_name_the_module_the_bom_orders() -> None:
    """Rev B's and rev C's BOMs order a Pico 2 W (their ticks are not surely under 1 ms on an
    RP2040), rev A's a Pico W; the pin map and the wiring picture say which, as U1 in the
    BOM."""
    for rev, module, mpn in (("rev-a", "Pico W (RP2040)", "SC0918"),
                             ("rev-b", "Pico 2 W (RP2350)", "SC1633"),
                             ("rev-c", "Pico 2 W (RP2350)", "SC1633")):
        pins = (ROOT / "hardware" / rev / "pins.md").read_text()
        assert pins.splitlines()[0] == f"# {rev}: pin map, {module}"
        svg = ET.fromstring((ROOT / "hardware" / rev / "wiring.svg").read_text())
        assert module in [t.text for t in svg.iter("{http://www.w3.org/2000/svg}text")]
        assert f"U1,1,Raspberry Pi,{mpn}," in (ROOT / "hardware" / rev / "bom.csv").read_text()


def test_the_address_straps_are_the_datasheets() -> None:
    """INA226 (SBOS547, its address table): A1 and A0 each tied to GND, VS, SDA or SCL; 0x40
    is both to GND, 0x45 both to VS, 0x49 A1 to SDA and A0 to VS."""
    text = (ROOT / "hardware" / "rev-a" / "pins.md").read_text()
    assert "| 0 | 0x40 | A1=GND, A0=GND |" in text
    assert "| 5 | 0x45 | A1=VS, A0=VS |" in text
    assert "| 9 | 0x49 | A1=SDA, A0=VS |" in text



def test_rev_c_pins_are_the_smart_switches() -> None:
    """Rev C: IN0/IN1 of each dual part are the enable pins, one DEN per part, one shared DSEL,
    the shared IS node on ADC1 (GPIO 27), and no I2C."""
    rows = [line.split(",", 2) for line in
            (ROOT / "hardware" / "rev-c" / "pins.csv").read_text().splitlines()[1:]]
    by_pin = {int(r[0]): (r[1], r[2]) for r in rows}
    # the parts' references are the BOM's (SW1-SW5; U1 is the Pico W there)
    assert by_pin[3] == ("switch enable", "channel 1: BTS7008-2EPA SW1 IN1")
    assert by_pin[16] == ("switch diagnosis enable", "BTS7008-2EPA SW5 DEN")
    assert by_pin[17][0] == "switch diagnosis select"
    assert by_pin[27][0] == "ADC" and "IS sense node" in by_pin[27][1]
    assert not any("I2C" in fn for fn, _ in by_pin.values())
    md = (ROOT / "hardware" / "rev-c" / "pins.md").read_text()
    assert "| 9 | SW5 | IN1 | GP16 | high |" in md
    ET.fromstring((ROOT / "hardware" / "rev-c" / "wiring.svg").read_text())


def test_rev_b_channels_name_their_chip_input() -> None:
    md = (ROOT / "hardware" / "rev-b" / "pins.md").read_text()
    assert "| 2 | 0x40 input 3 | A0=GND |" in md and "| 9 | 0x43 input 2 | A0=SCL |" in md
