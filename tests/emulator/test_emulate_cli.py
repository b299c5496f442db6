"""`dxboard emulate` as users run it: what it prints, bad input, a clean exit on SIGTERM."""

from __future__ import annotations

import re
import subprocess

import pytest

from tests.emulator.wire import DXBOARD, ROOT, TEDUSAR, Emulate


@pytest.mark.parametrize("args", [
    ["/nonexistent/robot"],
    [str(TEDUSAR), "--listen", "localhost"],
    [str(TEDUSAR), "--modbus", "1.2.3.4:99999"],
    [str(TEDUSAR), "--can", "nosuchbus:x"],
    [str(ROOT / "models")],  # a directory without emulator.yaml
])
def test_bad_input_is_one_line_exit_2(args: list[str]) -> None:
    p = subprocess.run([DXBOARD, "emulate", *args], capture_output=True, text=True, timeout=30)
    assert p.returncode == 2, p.stderr
    assert p.stdout == ""
    assert len(p.stderr.strip().splitlines()) == 1, p.stderr
    assert p.stderr.startswith("dxboard emulate: error: ")


def test_prints_urls_and_exits_cleanly() -> None:
    with Emulate("--modbus", "127.0.0.1:0", "--serial") as emu:
        assert re.fullmatch(r"tcp://127\.0\.0\.1:\d+", emu.urls["board"])
        assert re.fullmatch(r"control://127\.0\.0\.1:\d+", emu.urls["control"])
        assert re.fullmatch(r"modbus\+tcp://127\.0\.0\.1:\d+", emu.urls["modbus"])
        assert re.fullmatch(r"serial:///dev/pts/\d+", emu.urls["serial"])
        assert all(not u.endswith(":0") for u in emu.urls.values())
        assert emu.stop() == 0
