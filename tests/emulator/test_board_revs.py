"""``--board-rev rev-b`` and ``rev-c``: the same shipped ``boot.py`` and ``main.py`` on the other
revisions' parts, wired by ``emulator.parts.wiring`` (the one wiring the emulator's bench uses).

One ``micropython`` process a revision for the module (rev A has its own module,
``test_board_rev.py``): rev B reads four INA3221 models (three channels a chip), rev C five
dual PROFET smart switches through one IS node on the ADC. Each boots, reads its parts near the
electronics' true currents, and takes one part fault as a board would: an INA3221 that does not
acknowledge is a sensor fault of its three channels only; a short behind a PROFET channel trips
that channel by the part's own protection and not the other half of the same part (there the
protected computer). A part fault the revision's part does not have is refused naming the ones
it has. The conformance peers (spec-only client, pymodbus, Modbus TCP) run against both through
``RUNTIMES`` (``tests/emulator/wire.py``).
"""

from __future__ import annotations

import subprocess
from collections.abc import Iterator

import pytest

from emulator.faults import FaultError
from emulator.sim import Emulator
from tests.emulator.wire import DEVICES, DXBOARD, RUNTIMES, Emulate, board_bench, devices_on

PC, HOKUYO, KINECT, ROUTER, THERMAL_CAMERA = 2, 3, 4, 5, 6
# the part's own error on top of the loads' noise: INA3221 4 mA a count (40 uV over 10 mOhm);
# a PROFET's kILIS band (+-34 % at 50 mA to +-4 % from 5 A) and the ADC's 13 mA a count
TOLERANCE = {"rev-b": 0.15, "rev-c": 0.3}


@pytest.fixture(scope="module", params=["rev-b", "rev-c"])
def bench(request: pytest.FixtureRequest,
          tmp_path_factory: pytest.TempPathFactory) -> Iterator[tuple[str, Emulator]]:
    rev: str = request.param
    with board_bench(rev, tmp_path_factory.mktemp("flash-" + rev)) as (emu, _rt):
        yield rev, emu


@pytest.fixture
def emu(bench: tuple[str, Emulator]) -> Iterator[Emulator]:
    """The board with every device on and no fault; faults cleared after the test."""
    e = bench[1]
    devices_on(e)
    try:
        yield e
    finally:
        e.clear()
        e.advance(500)


def test_the_shipped_main_boots_and_reads_its_parts(bench: tuple[str, Emulator],
                                                    emu: Emulator) -> None:
    st = emu.status()
    assert st["config_status"] == "ok"
    assert abs(st["input_mv"] - emu.electronics.input_mv) < 0.02 * emu.electronics.input_mv
    for ch in (*DEVICES, PC):
        c = st["channels"][ch]
        # rev C measures from 100 mA: the thermal camera's 80 mA is low, not measured (a live
        # flag, not a fault); every other channel, and every channel of rev B, has none
        low = bench[0] == "rev-c" and ch == THERMAL_CAMERA
        assert c["state"] == "on" and c["physical"] and c["live"] == (["low"] if low else []), c
    read = true = 0.0
    for _ in range(5):  # the loads are noisy: what the parts read against the truth, summed
        emu.advance(200)
        chans = emu.status()["channels"]
        read += sum(c["current_ma"] for c in chans)
        true += sum(c["true_ma"] for c in chans)
    assert abs(read - true) < TOLERANCE[bench[0]] * true, (read, true)


def test_the_firmware_runs_on_the_simulated_clock(emu: Emulator) -> None:
    before = emu.status()
    emu.advance(3000)
    after = emu.status()
    assert after["now_ms"] - before["now_ms"] == 3000
    assert after["uptime_ms"] - before["uptime_ms"] == 3000
    assert after["boots"] == before["boots"]


def test_one_part_fault_as_the_revision_has_it(bench: tuple[str, Emulator],
                                               emu: Emulator) -> None:
    chans = emu.status()["channels"]
    if bench[0] == "rev-b":  # INA3221 1 senses channels 3-5: a NACK blinds the three
        emu.inject("hokuyo", "chip_nack", {})
        emu.advance(200)
        chans = emu.status()["channels"]
        for ch in (HOKUYO, KINECT, ROUTER):
            c = chans[ch]
            assert "sensor" in c["live"] and c["state"] == "on" and c["physical"], c
        assert not chans[PC]["live"] and chans[PC]["current_ma"] > 0
    else:  # PROFET 1: the computer on IN0, hokuyo on IN1; the short behind IN1 only
        emu.inject("hokuyo", "switch_short", {})
        emu.advance(200)
        chans = emu.status()["channels"]
        c = chans[HOKUYO]
        assert c["state"] == "tripped" and "short" in c["live"] and not c["physical"], c
        pc = chans[PC]
        assert pc["state"] == "on" and pc["physical"] and not pc["live"], pc
        assert pc["current_ma"] > 0
    emu.clear("hokuyo")
    emu.advance(1500)  # the chip answers again / the firmware's retry switches it on again
    c = emu.status()["channels"][HOKUYO]
    assert c["state"] == "on" and not c["live"] and c["current_ma"] > 0, c


def test_a_fault_the_part_does_not_have_is_refused(bench: tuple[str, Emulator],
                                                   emu: Emulator) -> None:
    wrong, has = ("switch_short", "chip_nack") if bench[0] == "rev-b" else \
        ("chip_nack", "switch_short")
    with pytest.raises(FaultError, match=has) as got:
        emu.inject("hokuyo", wrong, {})
    assert len(str(got.value).splitlines()) == 1
    assert not emu.faults()  # nothing recorded for it


def test_the_command_line_refuses_a_fault_the_part_lacks_in_one_line() -> None:
    """``dxboard inject`` on a running ``emulate --board-rev rev-c``: a shunt monitor's fault is
    refused (exit 2, one line naming the switch's faults); the switch's own is injected."""
    with Emulate(*RUNTIMES["rev-c"]) as board:
        def inject(fault: str) -> subprocess.CompletedProcess[str]:
            return subprocess.run([DXBOARD, "inject", board.urls["control"], "hokuyo", fault],
                                  capture_output=True, text=True, timeout=60)

        refused = inject("chip_nack")
        assert refused.returncode == 2 and refused.stdout == "", refused
        assert len(refused.stderr.strip().splitlines()) == 1, refused.stderr
        assert "switch_short" in refused.stderr and "Traceback" not in refused.stderr
        done = inject("switch_short")
        assert done.returncode == 0, done.stderr
        assert "injected switch_short on 3" in done.stdout
