"""``emulator.main``: signals at any moment of the start end it cleanly; clean-up agrees."""

from __future__ import annotations

import contextlib
import io
import os
import signal
import subprocess
import threading
import time
from pathlib import Path

import pytest

from emulator.main import Options, StartError, run, start, url_lines
from tests.emulator.wire import DXBOARD, KEY, TEDUSAR


def _full_pipe() -> tuple[int, int]:
    """A pipe whose buffer is already full: the next write to it blocks."""
    r, w = os.pipe()
    os.set_blocking(w, False)
    with contextlib.suppress(BlockingIOError):
        while True:
            os.write(w, b"\n" * 4096)
    os.set_blocking(w, True)
    return r, w


def _blocked_writing(pid: int) -> bool:
    try:
        return "pipe_write" in Path(f"/proc/{pid}/wchan").read_text()
    except OSError:
        return False


@pytest.mark.skipif(not Path("/proc/self/wchan").exists(), reason="needs Linux /proc")
def test_sigterm_while_printing_the_urls_exits_0(tmp_path: Path) -> None:
    """The handlers are installed before anything is printed: a SIGTERM that arrives while
    the URLs are being written (here: the write blocks on a full pipe) is a clean stop."""
    env = dict(os.environ, DXBOARD_KEY=KEY.hex())
    r, w = _full_pipe()
    err = (tmp_path / "stderr").open("w")
    proc = subprocess.Popen([DXBOARD, "emulate", str(TEDUSAR), "--serial"], stdout=w,
                            stderr=err, env=env)
    os.close(w)
    try:
        deadline = time.monotonic() + 60
        while not _blocked_writing(proc.pid):
            assert proc.poll() is None and time.monotonic() < deadline, "never printed"
            time.sleep(0.02)
        proc.send_signal(signal.SIGTERM)
        out = b""
        while chunk := os.read(r, 65536):  # unblock it; read to the end
            out += chunk
        code = proc.wait(30)
    finally:
        os.close(r)
        if proc.poll() is None:
            proc.kill()
    assert code == 0, (tmp_path / "stderr").read_text()
    assert b"board: tcp://" in out and b"serial: serial://" in out


def test_signal_during_start_stops_after_start(monkeypatch: pytest.MonkeyPatch) -> None:
    """A SIGINT delivered while the board is still starting is not lost and not fatal."""
    import emulator.main as main

    real_start = main.start

    def start_with_a_signal(opts: Options, stack: contextlib.ExitStack) -> dict[str, str]:
        os.kill(os.getpid(), signal.SIGINT)  # handled at once, on this (the main) thread
        return real_start(opts, stack)

    monkeypatch.setattr(main, "start", start_with_a_signal)
    out = io.StringIO()
    old = signal.getsignal(signal.SIGINT)
    assert run(Options(TEDUSAR, key=KEY), out) == 0
    assert signal.getsignal(signal.SIGINT) is old  # handlers restored
    assert out.getvalue().startswith("board: tcp://127.0.0.1:")


def test_failure_half_way_undoes_what_started() -> None:
    """The control endpoint and the native front end started; then the tug front end cannot
    listen: every part started is stopped again (no thread, no listening socket left
    behind)."""
    with contextlib.closing(__import__("socket").socket()) as busy:
        busy.bind(("127.0.0.1", 0))
        busy.listen()
        port = busy.getsockname()[1]
        before = threading.active_count()
        with pytest.raises(StartError, match=r"front ends: .*address already in use"), \
                contextlib.ExitStack() as stack:
            start(Options(TEDUSAR, key=KEY, tug=("127.0.0.1", port)), stack)
        assert threading.active_count() == before


def test_url_lines_order() -> None:
    urls = {"board": "tcp://h:1", "device hokuyo": "tcp://h:5", "serial": "serial:///dev/x",
            "control": "control://h:2", "modbus": "modbus+tcp://h:3"}
    assert url_lines(urls) == ["board: tcp://h:1", "control: control://h:2",
                               "modbus: modbus+tcp://h:3", "serial: serial:///dev/x",
                               "device: hokuyo tcp://h:5"]
