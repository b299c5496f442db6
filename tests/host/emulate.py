"""``dxboard emulate`` as a subprocess, as users start it: the URLs it prints, and stopping it."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
KEY_HEX = "000102030405060708090a0b0c0d0e0f"
ENV = {**os.environ, "DXBOARD_KEY": KEY_HEX, "PYTHONPATH": str(ROOT)}


class Emulate:
    """One ``dxboard emulate models/tedusar ...`` process and the URLs it printed."""

    def __init__(self, *options: str, env: dict[str, str] | None = None) -> None:
        cmd = [sys.executable, "-m", "host.cli", "emulate", str(ROOT / "models" / "tedusar"),
               *options]
        self.proc = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                                     text=True, env={**ENV, **(env or {})}, cwd=ROOT)
        self.urls: dict[str, str] = {}
        deadline = time.monotonic() + 120  # generous: a busy machine starts it slowly
        assert self.proc.stdout is not None
        while "control" not in self.urls or len(self.urls) < 2 + self._extra(options):
            line = self.proc.stdout.readline()
            if not line or time.monotonic() > deadline:
                self.kill()  # else reading its stderr waits for a live process forever
                err = self.proc.stderr.read() if self.proc.stderr else ""
                raise RuntimeError(f"dxboard emulate did not start: {err}")
            name, _, url = line.strip().partition(": ")
            self.urls[name] = url

    @staticmethod
    def _extra(options: tuple[str, ...]) -> int:
        return sum(o in ("--serial", "--modbus", "--can", "--tug") for o in options)

    def kill(self) -> None:
        if self.proc.poll() is None:
            self.proc.send_signal(signal.SIGKILL)
        self.proc.wait(10)

    def stop(self) -> None:
        if self.proc.poll() is None:
            self.proc.send_signal(signal.SIGTERM)
            try:
                self.proc.wait(10)
            except subprocess.TimeoutExpired:
                self.kill()
