"""``--board-rev rev-a``: the shipped ``boot.py`` and ``main.py`` on register-level part models.

One ``micropython`` process for the module (``BoardRuntime``) runs the unmodified firmware
files under the emulator on the simulated clock, in lock-step with the electronics: it boots,
reads its ten INA226 models over the model of ``machine.I2C``, and each part fault of the chip
model (``chip_*``) reaches the board as the firmware's drivers see it: a NACK or a wrong chip
is a sensor fault of that channel only, a bus held low one of every channel, and neither
switches the protected computer off; a chip that reset is configured again. The electronics'
own faults and the resets the emulator makes (soft, watchdog) still work. The command line
refuses an unknown revision with the known ones.
"""

from __future__ import annotations

import subprocess
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest

from emulator.board_rt import BoardRuntime
from emulator.faults import FaultError
from emulator.parts.ina226 import CONFIG_POR
from emulator.sim import Emulator
from firmware.hal.ina226 import CONFIG_TICK, calibration
from host.board import BoardClient
from host.board.types import ChannelState
from protocol.constants import F_SENSOR
from tests.emulator.conftest import tedusar
from tests.emulator.wire import (
    DEVICES,
    DXBOARD,
    KEY,
    RUNTIMES,
    TEDUSAR,
    Emulate,
    board_bench,
    devices_on,
)
from tests.wait import wait_until_async

PC, HOKUYO, KINECT, ROUTER = 2, 3, 4, 5


@pytest.fixture(scope="module")
def bench(tmp_path_factory: pytest.TempPathFactory) -> Iterator[tuple[Emulator, BoardRuntime]]:
    with board_bench("rev-a", tmp_path_factory.mktemp("flash")) as got:
        yield got


@pytest.fixture
def emu(bench: tuple[Emulator, BoardRuntime]) -> Iterator[Emulator]:
    """The board with every device on and no fault; faults cleared after the test."""
    e = bench[0]
    devices_on(e)
    try:
        yield e
    finally:
        e.clear()
        e.advance(500)


def channel(e: Emulator, ch: int) -> dict[str, Any]:
    got: dict[str, Any] = e.status()["channels"][ch]
    return got


def test_the_shipped_main_boots_and_reads_its_chips(emu: Emulator) -> None:
    st = emu.status()
    assert st["config_status"] == "ok"
    assert abs(st["input_mv"] - emu.electronics.input_mv) < 0.02 * emu.electronics.input_mv
    for ch in (*DEVICES, PC):
        c = st["channels"][ch]
        assert c["state"] == "on" and c["physical"] and not c["live"], c
    # every reading is a real INA226 average of the noisy loads: near the true current
    total_read = sum(c["current_ma"] for c in st["channels"])
    total_true = sum(c["true_ma"] for c in st["channels"])
    assert abs(total_read - total_true) < 0.15 * total_true, (total_read, total_true)


def test_the_firmware_runs_on_the_simulated_clock(emu: Emulator) -> None:
    before = emu.status()
    emu.advance(5000)  # five simulated seconds, however long they take here
    after = emu.status()
    assert after["now_ms"] - before["now_ms"] == 5000
    assert after["uptime_ms"] - before["uptime_ms"] == 5000
    assert after["boots"] == before["boots"]


def test_a_nack_is_a_sensor_fault_of_that_channel_only(emu: Emulator) -> None:
    emu.inject("hokuyo", "chip_nack", {})
    emu.advance(200)
    c = channel(emu, HOKUYO)
    assert "sensor" in c["live"] and c["state"] == "on" and c["physical"], c
    assert all(not channel(emu, ch)["live"] for ch in (PC, KINECT, ROUTER))
    emu.clear("hokuyo", "chip_nack")
    emu.advance(200)
    c = channel(emu, HOKUYO)
    assert not c["live"] and c["current_ma"] > 0, c


def test_a_bus_held_low_never_switches_the_protected_computer_off(emu: Emulator) -> None:
    emu.inject(ROUTER, "chip_stuck_low", {})
    emu.advance(500)
    st = emu.status()
    assert all("sensor" in c["live"] for c in st["channels"]), st["channels"]
    pc = st["channels"][PC]
    assert pc["state"] == "on" and pc["physical"], pc
    emu.clear(ROUTER)
    emu.advance(500)
    assert not any(c["live"] for c in emu.status()["channels"])


def test_a_chip_that_reset_is_configured_again(bench: tuple[Emulator, BoardRuntime],
                                               emu: Emulator) -> None:
    rt = bench[1]
    assert rt.registers(KINECT)[0] == CONFIG_TICK
    emu.inject(KINECT, "chip_reset", {})
    regs = rt.registers(KINECT)
    assert regs[0] == CONFIG_POR and regs[5] == 0  # back at power-on: CALIBRATION 0
    emu.advance(300)  # the driver checks one chip's CONFIG a tick: ten chips in 100 ms
    regs = rt.registers(KINECT)
    assert regs[0] == CONFIG_TICK and regs[5] == calibration(10000), regs
    assert not channel(emu, KINECT)["live"]


def test_a_wrong_chip_is_a_sensor_fault_after_a_soft_reboot(emu: Emulator) -> None:
    boots = emu.status()["boots"]
    emu.inject(KINECT, "chip_die_id", {"id": "12832"})  # an INA3221 answers at its address
    assert emu.board.request_reboot() == 0
    emu.advance(1000)
    st = emu.status()
    assert st["boots"] == boots + 1 and st["reset_cause"] == "soft"
    assert "sensor" in st["channels"][KINECT]["live"]
    assert st["channels"][PC]["state"] == "on"


def test_the_watchdog_resets_the_board(emu: Emulator) -> None:
    boots = emu.status()["boots"]
    emu.inject("board", "wdt_reset", {})
    emu.advance(4000)
    st = emu.status()
    assert st["boots"] == boots + 1 and st["reset_cause"] == "watchdog"
    assert st["channels"][PC]["state"] == "on"


def test_the_electronics_faults_still_work(emu: Emulator) -> None:
    emu.inject("hokuyo", "short", {})
    emu.advance(200)
    c = channel(emu, HOKUYO)
    assert c["state"] in ("tripped", "latched") and "short" in c["sticky"], c
    assert channel(emu, PC)["state"] == "on"


def test_part_faults_need_part_models() -> None:
    e = tedusar()
    with pytest.raises(FaultError, match="--board-rev"):
        e.inject("hokuyo", "chip_nack", {})


@pytest.mark.parametrize(("args", "said"), [
    (["--runtime", "micropython", "--board-rev", "rev-z"], "rev-a"),
    (["--board-rev", "rev-a"], "--runtime micropython"),
    (["--runtime", "micropython", "--board-rev", "rev-a", "--can", "virtual:x"], "CAN"),
])
def test_bad_revision_options_are_one_line_exit_2(args: list[str], said: str) -> None:
    p = subprocess.run([DXBOARD, "emulate", str(TEDUSAR), *args], capture_output=True,
                       text=True, timeout=60, cwd=Path(__file__).resolve().parents[2])
    assert p.returncode == 2, p.stderr
    assert p.stdout == ""
    assert len(p.stderr.strip().splitlines()) == 1, p.stderr
    assert said in p.stderr


def test_a_deep_brownout_holds_the_board_in_reset(emu: Emulator) -> None:
    boots = emu.status()["boots"]
    emu.inject("board", "brownout", {"volts": "3", "seconds": "0.5"})
    emu.advance(200)
    assert not any(s.closed for s in emu.electronics.switches)  # in reset: every switch open
    emu.advance(1500)
    st = emu.status()
    assert st["boots"] == boots + 1
    assert st["reset_cause"] == "power_on"  # the RP2040 restarts by its power-on reset
    assert st["channels"][PC]["state"] == "on"


async def test_a_part_fault_injected_from_the_command_line_reaches_the_host() -> None:
    """``dxboard inject CONTROL chip_nack`` on a running ``emulate --board-rev``: the host's
    own client reads the ``sensor`` fault of that channel; no switch moves for it."""
    with Emulate(*RUNTIMES["rev-a"]) as board:
        done = subprocess.run([DXBOARD, "inject", board.urls["control"], "hokuyo",
                               "chip_nack"], capture_output=True, text=True, timeout=60)
        assert done.returncode == 0, done.stderr
        assert "injected chip_nack on 3" in done.stdout
        async with BoardClient(board.urls["board"], KEY) as client:
            async def sensor_fault() -> ChannelState | None:
                ch = (await client.state()).channels[HOKUYO]
                return ch if ch.live_faults & F_SENSOR else None

            got = await wait_until_async(sensor_fault, what="the sensor fault of hokuyo")
            assert got is not None and got.state_name == "off"  # left as it was (off)
            # the computer's channel stays switched on (a busy machine may still find it in
            # the inrush window its power-up at boot began)
            assert (await client.state()).channels[PC].state_name in ("inrush", "on")
