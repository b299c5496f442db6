"""A board that runs on its own: ``dxboard emulate SYSTEM --robot`` as a real process, and
``dxboard run --board`` daemons against it (``RunningDaemon``), for the tests and benchmarks
in which the board outlives a daemon (``kill -9`` and a restart)."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import threading
from pathlib import Path

import yaml

from tests.daemon.runner import ROOT, RunningDaemon
from tests.wait import wait_until


class Board:
    """``dxboard emulate SYSTEM --robot`` with a key file: its URLs and device lines."""

    def __init__(self, system: Path, key: Path) -> None:
        self.proc = subprocess.Popen(
            [sys.executable, "-m", "host.cli", "emulate", str(system), "--robot",
             "--key-file", str(key)], cwd=ROOT, stdout=subprocess.PIPE,
            stderr=subprocess.DEVNULL, text=True, start_new_session=True)
        self.lines: list[str] = []
        self._reader = threading.Thread(target=self._read, daemon=True)
        self._reader.start()
        wanted = len(_devices(system))
        wait_until(lambda: len(self.devices()) == wanted and "control" in self.urls(), 120,
                   "the emulated board's URLs", show=lambda: self.lines[-10:])

    def _read(self) -> None:
        assert self.proc.stdout is not None
        for line in self.proc.stdout:
            self.lines.append(line.strip())

    def urls(self) -> dict[str, str]:
        return dict(x.split(": ", 1) for x in list(self.lines)  # type: ignore[misc]
                    if ": " in x and not x.startswith("device: "))

    def devices(self) -> dict[str, str]:
        return dict(x[len("device: "):].split(" ", 1) for x in list(self.lines)  # type: ignore[misc]
                    if x.startswith("device: "))

    def stop(self) -> None:
        if self.proc.poll() is None:
            os.killpg(self.proc.pid, signal.SIGTERM)
            try:
                self.proc.wait(20)
            except subprocess.TimeoutExpired:
                os.killpg(self.proc.pid, signal.SIGKILL)
                self.proc.wait(10)


def _devices(system: Path) -> list[str]:
    return list(yaml.safe_load((system / "robot.yaml").read_text())["devices"])


def daemon(tmp: Path, b: Board, system: Path, key: Path) -> RunningDaemon:
    """``dxboard run SYSTEM --board URL`` with the key file, journal in ``tmp`` (made here),
    its nodes given the board's devices (``DXBOARD_DEVICES``)."""
    tmp.mkdir()
    return RunningDaemon(tmp, system, ("--key-file", str(key)), board=b.urls()["board"],
                         env={"DXBOARD_DEVICES": json.dumps(b.devices())})
