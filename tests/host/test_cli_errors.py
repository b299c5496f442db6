"""One clear line and exit 2, never a traceback: the CLI findings of issues 11 and 12
(``config set board modbus_allow=...``, a value out of range, switching without a key,
``protocol decode`` of something that is not a frame)."""

from __future__ import annotations

import json
import subprocess
import sys
from collections.abc import Iterator

import pytest

from tests.host.emulate import ENV, ROOT, Emulate
from tests.host.test_cli_board import board


@pytest.fixture(scope="module")
def emu() -> Iterator[Emulate]:
    e = Emulate()
    yield e
    e.stop()


def one_line_error(done: subprocess.CompletedProcess[str], *needles: str) -> None:
    assert done.returncode == 2, (done.stdout, done.stderr)
    assert "Traceback" not in done.stderr
    assert done.stderr.count("\n") == 1, done.stderr
    for needle in needles:
        assert needle in done.stderr, done.stderr


def test_config_set_modbus_allow_takes_dotted_addresses(emu: Emulate) -> None:
    url = emu.urls["board"]
    done = board(url, "config", "set", "board", "modbus_allow=127.0.0.1,10.0.0.2")
    assert done.returncode == 0, done.stderr
    got = json.loads(board(url, "config", "get", "board", "--json").stdout)
    assert got["modbus_allow"] == ["127.0.0.1", "10.0.0.2"]
    done = board(url, "config", "set", "board", "modbus_allow=")
    assert done.returncode == 0, done.stderr
    assert json.loads(board(url, "config", "get", "--json").stdout)["modbus_allow"] == []
    one_line_error(board(url, "config", "set", "board", "modbus_allow=localhost"),
                   "modbus_allow", "not an IPv4 address")


def test_config_values_out_of_range_are_named(emu: Emulate) -> None:
    url = emu.urls["board"]
    one_line_error(board(url, "config", "set", "hokuyo", "rated_ma=abc"),
                   "rated_ma", "1..60000")
    one_line_error(board(url, "config", "set", "board", "uv_warn_mv=70000"),
                   "uv_warn_mv", "0..65535")
    one_line_error(board(url, "config", "set", "hokuyo", "retry_ms=1,2,3,4,5,6,7,8,9"),
                   "retry_ms")
    one_line_error(board(url, "config", "set", "board", "key=00"), "unknown board setting")
    cfg = json.loads(board(url, "config", "get", "hokuyo", "--json").stdout)
    assert cfg["rated_ma"] == 1000  # nothing changed


@pytest.mark.parametrize("action", [["off", "kinect"], ["on", "kinect"], ["cycle", "kinect"],
                                    ["clear", "all"], ["config", "save"]])
def test_actuation_without_a_key_is_one_line(emu: Emulate, action: list[str]) -> None:
    one_line_error(board(emu.urls["board"], *action, key=None), "DXBOARD_KEY")


@pytest.mark.parametrize("hexes", [["00"], ["db58"], ["zz"], ["db5801040000000400"]])
def test_protocol_decode_of_no_frame_is_exit_2(hexes: list[str]) -> None:
    done = subprocess.run([sys.executable, "-m", "host.cli", "protocol", "decode", *hexes],
                          capture_output=True, text=True, timeout=60, env=ENV, cwd=ROOT)
    one_line_error(done, "dxboard protocol: error:")


def test_protocol_decode_of_a_frame_is_exit_0() -> None:
    ping = "db58 01 03 0002 0004 deadbeef 0a02f422"
    done = subprocess.run([sys.executable, "-m", "host.cli", "protocol", "decode", "--as-board",
                           ping], capture_output=True, text=True, timeout=60, env=ENV, cwd=ROOT)
    assert done.returncode == 0, done.stderr
    assert "Ping(token=3735928559" in done.stdout
    done = subprocess.run([sys.executable, "-m", "host.cli", "protocol", "decode", ping],
                          capture_output=True, text=True, timeout=60, env=ENV, cwd=ROOT)
    one_line_error(done, "error 106", "--as-board")
