"""``dxboard flash`` for real: mpremote against the MicroPython interpreter's REPL on a pty.

The flashed tree is checked file by file against the sources, the config the board wrote is
read back, and then the flashed firmware boots in that same interpreter (an ``App`` on a small
HAL, with the flashed config loaded from the board's file system) through mpremote.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
from collections.abc import Iterator
from pathlib import Path

import pytest

from tests.host.repl import PtyRepl

ROOT = Path(__file__).resolve().parents[2]
KEY_HEX = "00112233445566778899aabbccddeeff"

# runs in the flashed interpreter: boot the firmware on a tiny HAL, print what it loaded
BOOT = """
import json
from firmware.app import App
from firmware.hal.storage import FileStorage
class Hal:
    n_channels = 10
    storage = FileStorage('')
    t = 0
    def ticks_ms(self): return self.t
    def read_currents_ma(self, out):
        for i in range(10): out[i] = 100 if self.sw[i] else 0
    def read_current_ma(self, ch): return 0
    def set_switch(self, ch, on): self.sw[ch] = on
    def read_switch(self, ch): return self.sw[ch]
    def read_input_mv(self): return 24000
    def wdt_feed(self): pass
    def reset_cause(self): return 0
    def random_bytes(self, n): return bytes(n)
    def reboot(self): pass
hal = Hal()
hal.sw = [False] * 10
app = App(hal)
app.start()
for i in range(100):
    hal.t += 10
    app.step()
b = app.board
print('BOOT', json.dumps({'status': b.cfg_status, 'names': [c.cfg['name'] for c in b.channels],
      'key': b.cfg['board']['key'], 'on': [i for i in range(10) if hal.sw[i]]}))
"""


@pytest.fixture
def repl(tmp_path: Path) -> Iterator[PtyRepl]:
    board = tmp_path / "board"
    board.mkdir()
    r = PtyRepl(board)
    yield r
    r.close()


def dxboard(*args: str, env: dict[str, str] | None = None) -> subprocess.CompletedProcess[str]:
    return subprocess.run([sys.executable, "-m", "host.cli", *args], capture_output=True,
                          text=True, timeout=240, cwd=ROOT, env={**os.environ, **(env or {})})


def mpremote_exec(device: str, code: str) -> str:
    done = subprocess.run([sys.executable, "-m", "mpremote", "connect", device, "resume",
                           "exec", code], capture_output=True, text=True, timeout=60)
    assert done.returncode == 0, done.stderr
    return done.stdout


def test_flash_deploys_verifies_and_boots(repl: PtyRepl, tmp_path: Path) -> None:
    cfg = tmp_path / "board.json"
    cfg.write_text((ROOT / "models" / "tedusar" / "board.json").read_text())
    stale = repl.root / "firmware"
    stale.mkdir()
    (stale / "old_module.py").write_text("raise SystemExit\n")
    done = dxboard("flash", "--port", repl.device, "--config", str(cfg),
                   env={"DXBOARD_KEY": KEY_HEX})
    assert done.returncode == 0, done.stderr
    out = done.stdout
    assert "verified" in out and "wrote the config (10 channels" in out and "key set" in out
    # the unix port cannot reset: flash says so, and does not claim it reset the board
    assert "cannot reset itself" in out and "reset the board" not in out
    # every source file arrived unchanged (but the two written for this board); no stale one
    generated = {"firmware/factory.py", "firmware/build.py"}
    for pkg in ("firmware", "protocol"):
        for src in (ROOT / pkg).rglob("*.py"):
            rel = src.relative_to(ROOT)
            if "__pycache__" in src.parts or rel.as_posix() in generated:
                continue
            assert (repl.root / rel).read_bytes() == src.read_bytes(), rel
    assert not (stale / "old_module.py").exists()
    assert (repl.root / "main.py").read_text().strip().endswith("import firmware.main")
    # the flashed configuration is built into the firmware as its factory configuration
    namespace: dict[str, object] = {}
    exec((repl.root / "firmware" / "factory.py").read_text(), namespace)
    factory = namespace["FACTORY"]
    assert isinstance(factory, dict) and factory["board"]["key"] == KEY_HEX
    assert factory["channels"][2]["name"] == "pc" and factory["channels"][2]["protected"]
    assert "BUILD = '" in (repl.root / "firmware" / "build.py").read_text()
    # the flashed firmware boots in the interpreter with the flashed config
    line = next(x for x in mpremote_exec(repl.device, BOOT).splitlines() if x.startswith("BOOT"))
    booted = json.loads(line[5:])
    assert booted["status"] == 0  # CFG_OK: loaded from the file flash wrote
    assert booted["names"][:4] == ["sensor_head", "laser_alignment", "pc", "hokuyo"]
    assert booted["key"] == KEY_HEX
    assert booted["on"] == [2]  # only "pc" has powerup in board.json


def test_flash_resets_and_checks_that_the_new_firmware_runs(tmp_path: Path) -> None:
    """A board that can reset is reset, and flash checks that it came back running the new
    build. On the unix port the flashed firmware cannot start (no I2C, no pins): flash must
    say that it did not come back running it, rather than that all went well (within the
    --wait it is given: the unix port boots in well under a second, and one mpremote exec on a
    busy machine takes seconds)."""
    board = tmp_path / "board"
    board.mkdir()
    r = PtyRepl(board, resettable=True)
    try:
        done = dxboard("flash", "--port", r.device, "--wait", "20")
        assert r.boots == 2  # it was reset, and booted again
        assert done.returncode == 2, done.stdout
        assert "does not run the new firmware within 20 s" in done.stderr
        assert "did not start" in done.stderr and "Traceback" not in done.stderr
        assert done.stderr.count("\n") == 1
    finally:
        r.close()


def test_flash_mpy_with_json_summary(repl: PtyRepl) -> None:
    done = dxboard("flash", "--port", repl.device, "--mpy", "--no-reset", "--json")
    assert done.returncode == 0, done.stderr
    summary = json.loads(done.stdout)
    assert summary["mpy"] is True and summary["reset"] is False
    assert summary["verified"] == summary["files"] > 20 and len(summary["build"]) == 16
    assert (repl.root / "firmware" / "board.mpy").exists()
    assert not (repl.root / "firmware" / "board.py").exists()
    code = "from firmware import config\nprint('N', len(config.defaults(3)['channels']))"
    out = mpremote_exec(repl.device, code)
    assert "N 3" in out


def test_flash_refuses_a_bad_config(repl: PtyRepl, tmp_path: Path) -> None:
    cfg = tmp_path / "bad.json"
    cfg.write_text(json.dumps({"board": {}, "channels": [{"name": "x", "rated_ma": -5}]}))
    done = dxboard("flash", "--port", repl.device, "--config", str(cfg), "--no-reset")
    assert done.returncode == 2
    assert "channel 0: rated_ma" in done.stderr and "Traceback" not in done.stderr
    assert not list(repl.root.iterdir())  # refused before anything was copied


def test_flash_missing_device_is_one_line() -> None:
    done = dxboard("flash", "--port", "/dev/does-not-exist")
    assert done.returncode == 2
    assert done.stderr.count("\n") == 1 and "no device /dev/does-not-exist" in done.stderr


def test_flash_wait_must_be_positive() -> None:
    done = dxboard("flash", "--port", "/dev/does-not-exist", "--wait", "0")
    assert done.returncode == 2
    assert done.stderr.count("\n") == 1 and "--wait 0 must be a number of seconds" in done.stderr


def test_flash_unknown_board_revision_is_one_line() -> None:
    done = dxboard("flash", "--port", "/dev/does-not-exist", "--board-rev", "rev-z")
    assert done.returncode == 2
    assert done.stderr.count("\n") == 1 and "no board revision 'rev-z'" in done.stderr
    assert "rev-a" in done.stderr


def test_collect_writes_the_board_revision(tmp_path: Path) -> None:
    from host.commands.flash import build_id, collect

    files = collect(False, tmp_path, None, "rev-a")
    assert files["board_rev"].read_text() == "rev-a\n"
    assert files["boot.py"].read_text().endswith("import firmware.boot\nfirmware.boot.run()\n")
    other = collect(False, tmp_path / "b", None, "rev-b")
    assert build_id(files) != build_id(other)  # the revision is part of the build
