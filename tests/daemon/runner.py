"""``dxboard run --emulate`` as a real subprocess, for the daemon's end-to-end tests.

``RunningDaemon`` starts it on free ports (web, zenoh) with a journal in a temporary folder,
reads the URLs it prints, and offers what a person would use: the JSON API (``status()``),
``dxboard inject`` on the printed control URL, the journal (``journal()``), and SIGINT.
"""

from __future__ import annotations

import contextlib
import json
import signal
import socket
import subprocess
import sys
import threading
import time
import urllib.request
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

from host.experiment.robot import fast_model
from host.journal import ActionRecord, Entry, JournalReader

ROOT = Path(__file__).resolve().parents[2]
TEDUSAR = ROOT / "models" / "tedusar"


def fast_copy(tmp: Path) -> Path:
    """``models/tedusar`` with short device boot times (``host.experiment.robot.fast_model``)."""
    return fast_model(TEDUSAR, tmp)


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


class RunningDaemon:
    def __init__(self, tmp: Path, system_dir: Path = TEDUSAR,
                 extra_args: tuple[str, ...] = ()) -> None:
        self.journal_path = tmp / "journal.sqlite"
        argv = [sys.executable, "-m", "host.cli", "run", str(system_dir), "--emulate",
                "--web", "127.0.0.1:0", "--journal", str(self.journal_path),
                "--zenoh", f"tcp/127.0.0.1:{free_port()}", *extra_args]
        self.err_path = tmp / "daemon.err"
        with self.err_path.open("wb") as err:
            self.proc = subprocess.Popen(argv, cwd=ROOT, stdout=subprocess.PIPE, stderr=err,
                                         text=True)
        self.urls: dict[str, str] = {}
        assert self.proc.stdout is not None
        while "journal" not in self.urls:
            line = self.proc.stdout.readline()
            if not line:
                raise AssertionError("dxboard run exited: " + self.err_path.read_text()[-2000:])
            name, _, rest = line.strip().partition(": ")
            self.urls[name] = rest
        # what it says on its terminal after the URLs, read as it comes (a pipe nobody read
        # would fill up)
        self.lines: list[str] = []
        self._reader = threading.Thread(target=self._read_terminal, daemon=True)
        self._reader.start()

    def _read_terminal(self) -> None:
        assert self.proc.stdout is not None
        for line in self.proc.stdout:
            self.lines.append(line.rstrip("\n"))

    def status(self) -> dict[str, Any]:
        with urllib.request.urlopen(self.urls["web"] + "api/status", timeout=5) as r:
            data: dict[str, Any] = json.load(r)
        return data

    def wait_for(self, what: Callable[[dict[str, Any]], bool], timeout: float = 20.0,
                 label: str = "") -> dict[str, Any]:
        end = time.monotonic() + timeout
        st = self.status()
        while not what(st):
            if time.monotonic() > end:
                raise AssertionError(f"timed out waiting for {label}; last status: "
                                     f"diagnoses={st['diagnoses']} repairs={st['repairs']}")
            time.sleep(0.1)
            st = self.status()
        return st

    def inject(self, *args: str) -> None:
        subprocess.run([sys.executable, "-m", "host.cli", "inject", self.urls["control"],
                        *args], check=True, cwd=ROOT, capture_output=True, timeout=10)

    def journal(self, kind: str | tuple[str, ...] | None = None) -> list[Entry]:
        return JournalReader(self.journal_path).query(kind=kind, limit=100000)

    def board(self, *args: str, key_file: Path) -> str:
        """``dxboard board BOARD_URL ARGS`` with the key file, as an operator would."""
        out = subprocess.run([sys.executable, "-m", "host.cli", "board", self.urls["board"],
                              *args, "--key-file", str(key_file)], check=True, cwd=ROOT,
                             capture_output=True, text=True, timeout=15)
        return out.stdout

    def interrupt(self, timeout: float = 20.0) -> int:
        self.proc.send_signal(signal.SIGINT)
        return self.proc.wait(timeout)

    def close(self) -> None:
        if self.proc.poll() is None:  # stop it as a person would; kill only if it hangs
            self.proc.send_signal(signal.SIGINT)
            try:
                self.proc.wait(20)
            except subprocess.TimeoutExpired:
                self.proc.kill()
                self.proc.wait()
        self._reader.join(5)
        if self.proc.stdout is not None:
            self.proc.stdout.close()


KEY = bytes(range(32))


def key_file(tmp: Path, key: bytes = KEY) -> Path:
    """A key file as ``--key-file`` wants it (hex, readable by its owner only)."""
    path = tmp / "key"
    path.write_text(key.hex())
    path.chmod(0o600)
    return path


def healthy(s: dict[str, Any]) -> bool:
    """The robot is up: board link up, nothing diagnosed, and every repair action finished."""
    return bool(s["board_link_up"]) and not s["diagnoses"] and bool(s["repairs"]) and all(
        r["state"] in ("succeeded", "failed", "timeout") for r in s["repairs"])


@contextlib.contextmanager
def healthy_robot(tmp: Path, heal_s: float = 90.0) -> Iterator[RunningDaemon]:
    """The fast virtual TEDUSAR robot under ``dxboard run --emulate`` with a key file, once it
    has powered up and is healthy (a module's shared daemon); stopped afterwards."""
    key = key_file(tmp)
    d = RunningDaemon(tmp, fast_copy(tmp), extra_args=("--key-file", str(key)))
    try:
        d.wait_for(healthy, heal_s, "the robot powered up and healthy")
        yield d
    finally:
        d.close()


def last_id(d: RunningDaemon, timeout: float = 10.0) -> int:
    """The journal's last id, once every action it shows started has its result journaled too
    (the page shows a result at once; the journal's writer thread commits it a moment later)."""
    end = time.monotonic() + timeout
    while True:
        entries = d.journal()
        acts = [e.payload for e in entries if isinstance(e.payload, ActionRecord)]
        started = {a.action_id for a in acts if a.finished is None}
        if started <= {a.action_id for a in acts if a.finished is not None} or (
                time.monotonic() > end):
            return max((e.id for e in entries), default=0)
        time.sleep(0.1)


def bad_sets(status: dict[str, Any]) -> list[set[str]]:
    return [set(d["bad"]) for d in status["diagnoses"]]


__all__ = [
    "KEY", "RunningDaemon", "bad_sets", "fast_copy", "free_port", "healthy", "healthy_robot",
    "key_file", "last_id",
]
