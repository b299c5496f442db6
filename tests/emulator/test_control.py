"""The control endpoint, driven by `dxboard inject` as a real subprocess, on the wall clock."""

from __future__ import annotations

import json
import socket
import subprocess
import sys
from collections.abc import Iterator
from pathlib import Path

import pytest

from emulator.control import Background
from tests.emulator.conftest import tedusar
from tests.wait import wait_until

ROOT = Path(__file__).resolve().parents[2]
_SCRIPT = Path(sys.executable).parent / "dxboard"
# The installed console script. Before `make` has installed the package, the same
# ``host.cli.main``, limited to the sub-command modules that exist yet.
_MAIN = ("import importlib.util as u, sys, host.cli as c; c.COMMANDS = {k: v for k, v in "
         "c.COMMANDS.items() if u.find_spec(v)}; sys.exit(c.main(sys.argv[1:]))")
DXBOARD = [str(_SCRIPT)] if _SCRIPT.exists() else [sys.executable, "-c", _MAIN]


@pytest.fixture(scope="module")
def bg() -> Iterator[Background]:
    with Background(tedusar()) as b:
        b.call(lambda: b.emu.board.switch(3, True))
        assert wait_for(lambda: b.call(lambda: b.emu.board.channels[3].state) == 2)  # ST_ON
        yield b


def inject(*args: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run([*DXBOARD, "inject", *args], capture_output=True, text=True,
                          timeout=30, cwd=ROOT)


def wait_for(pred, seconds: float = 30.0) -> bool:  # type: ignore[no-untyped-def]
    return bool(wait_until(pred, seconds, "the emulator's state"))


def test_inject_short_trips_the_channel_and_clear_removes_it(bg: Background) -> None:
    r = inject(bg.url, "hokuyo", "short")
    assert r.returncode == 0, r.stderr
    assert "injected short on 3" in r.stdout
    assert wait_for(lambda: bg.call(lambda: bg.emu.board.channels[3].sticky) & 1)  # F_SHORT
    r = inject(bg.url.removeprefix("control://"), "clear")
    assert r.returncode == 0 and "cleared 1" in r.stdout
    assert bg.call(lambda: bg.emu.active) == {}


def test_parameters_are_typed_by_the_emulator(bg: Background) -> None:
    r = inject(bg.url, "board", "link_delay", "ms=120")
    assert r.returncode == 0, r.stderr
    assert bg.call(lambda: dict(bg.emu.link_faults)) == {"link_delay": {"ms": 120.0}}
    assert inject(bg.url, "clear").returncode == 0


@pytest.mark.parametrize(("args", "message"), [
    (("hokuyo", "melt"), "unknown fault 'melt'"),
    (("hokuyo", "overcurrent", "amps=x"), "must be a number"),
    (("toaster", "short"), "no channel 'toaster'"),
    (("hokuyo", "overcurrent", "amps"), "write parameters as key=value"),
])
def test_bad_requests_are_one_line_errors(bg: Background, args, message) -> None:  # type: ignore[no-untyped-def]
    r = inject(bg.url, *args)
    assert r.returncode == 2
    assert message in r.stderr and len(r.stderr.strip().splitlines()) == 1
    assert bg.call(lambda: bg.emu.active) == {}


def test_unreachable_endpoint_is_a_one_line_error() -> None:
    s = socket.socket()
    s.bind(("127.0.0.1", 0))
    port = s.getsockname()[1]
    s.close()
    r = inject(f"127.0.0.1:{port}", "1", "short")
    assert r.returncode == 2 and "cannot reach" in r.stderr
    assert len(r.stderr.strip().splitlines()) == 1
    assert inject("nonsense", "1", "short").returncode == 2


def test_protocol_survives_garbage_and_answers_status(bg: Background) -> None:
    host, port = bg.address
    with socket.create_connection((host, port), timeout=30) as s:
        f = s.makefile("rwb")
        for line in (b"not json\n", b"[1]\n", b'{"op": "dance"}\n'):
            f.write(line)
            f.flush()
            assert json.loads(f.readline())["ok"] is False
        f.write(b'{"op": "status"}\n')
        f.flush()
        status = json.loads(f.readline())["status"]
        assert status["channels"][2]["name"] == "pc"
        f.write(b'{"op": "hello"}\n')
        f.flush()
        assert "hang" in json.loads(f.readline())["faults"]
