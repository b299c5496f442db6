"""``dxboard emulate --flash DIR``: the emulated flash is a directory, so `config save` lasts."""

from __future__ import annotations

from pathlib import Path

from host.board import BoardClient
from tests.emulator.wire import KEY, Emulate


async def test_saved_config_survives_a_restart(tmp_path: Path) -> None:
    flash = tmp_path / "flash"
    with Emulate("--flash", str(flash)) as emu:
        async with BoardClient(emu.urls["board"], KEY) as board:
            assert (await board.configurator.get_channel_config("hokuyo"))["rated_ma"] == 1000
            await board.configurator.set_channel_config("hokuyo", rated_ma=1234)
            await board.configurator.save_config()
        assert emu.stop() == 0
    assert any(flash.iterdir())
    with Emulate("--flash", str(flash)) as emu:
        async with BoardClient(emu.urls["board"], KEY) as board:
            assert (await board.configurator.get_channel_config("hokuyo"))["rated_ma"] == 1234
            state = await board.state()
            assert state.config_status == 0  # CFG_OK
    with Emulate() as emu:  # without --flash: memory, a fresh board.json each run
        async with BoardClient(emu.urls["board"], KEY) as board:
            assert (await board.configurator.get_channel_config("hokuyo"))["rated_ma"] == 1000


def test_unusable_flash_dir_is_one_line(tmp_path: Path) -> None:
    import subprocess

    from tests.emulator.wire import DXBOARD, TEDUSAR

    blocker = tmp_path / "file"
    blocker.write_text("not a directory")
    p = subprocess.run([DXBOARD, "emulate", str(TEDUSAR), "--flash", str(blocker / "x")],
                       capture_output=True, text=True, timeout=60)
    assert p.returncode == 2 and len(p.stderr.strip().splitlines()) == 1, p.stderr
    assert "--flash" in p.stderr


async def test_losing_the_saved_config_keeps_the_pc_on(tmp_path: Path) -> None:
    """Both stored copies damaged: the board boots the configuration it was flashed with
    (board.json): the pc channel on and protected, and the key still switches."""
    flash = tmp_path / "flash"
    with Emulate("--flash", str(flash)) as emu:
        async with BoardClient(emu.urls["board"], KEY) as board:
            await board.configurator.set_channel_config("hokuyo", rated_ma=1234)
            await board.configurator.save_config()
            await board.configurator.save_config()
    copies = sorted(flash.glob("config.*.json"))
    assert len(copies) == 2
    for path in copies:
        data = bytearray(path.read_bytes())
        data[len(data) // 2] ^= 0x01  # one bit flipped in each
        path.write_bytes(bytes(data))
    with Emulate("--flash", str(flash)) as emu:
        async with BoardClient(emu.urls["board"], KEY) as board:
            state = await board.state()
            assert state.config_status == 2  # CFG_CORRUPT: said, and survived
            assert state.channels[2].name == "pc" and state.channels[2].commanded
            assert (await board.configurator.get_channel_config("pc"))["protected"] is True
            assert (await board.configurator.get_channel_config("hokuyo"))["rated_ma"] == 1000
            assert (await board.switch("kinect", True)).physical  # the key still works
