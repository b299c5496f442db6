"""A board that runs on its own: ``dxboard emulate`` as a child process, driven as a person would.

For the tests and benchmarks in which the board is not the daemon's child (``dxboard run --board
URL``): a daemon killed (``kill -9``) and restarted against it, a front end (serial, Modbus,
CAN, the original TEDUSAR wire format) read by a client of its own. ``RunningBoard(system,
*extra, key_file=... | key=..., robot=True)`` starts ``dxboard emulate SYSTEM [--robot]`` as a
``host.launch.procs.Child`` with its key (a key file, or the key in its environment; neither: no
key) and waits (starting again when a port it picked was taken meanwhile) until it printed
``board``, ``control``, a URL for each front end asked for, every device of the robot (and
``world`` with ``--world``); it offers its URLs, ``dxboard board`` and ``dxboard inject``
against it, and a bounded stop. ``daemon_on`` starts ``dxboard run --board`` against it
(``host.launch.running.RunningDaemon``), its nodes given the board's devices.
"""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
from collections.abc import Mapping
from pathlib import Path

import yaml

from host.launch.ports import clashed
from host.launch.procs import Child, Printed
from host.launch.running import MIN_WAIT_S, ROOT, RunningDaemon

BOARD_START_S = 120.0  # a busy machine starts it slowly; this only bounds a failure
STOP_GRACE_S = 20.0
FRONT_ENDS = ("--serial", "--modbus", "--can", "--tug")  # each prints a URL line of its own
TRIES = 3


class RunningBoard(Printed):
    """``dxboard emulate SYSTEM [--robot] [EXTRA...]`` with a key; see the module."""

    def __init__(self, system: Path, *extra: str, key_file: Path | None = None,
                 key: bytes | None = None, robot: bool = True,
                 env: Mapping[str, str] | None = None) -> None:
        self.keyed = ["--key-file", str(key_file)] if key_file is not None else []
        self.env = {k: v for k, v in os.environ.items() if k != "DXBOARD_KEY"}  # no key: none
        self.env.update({"DXBOARD_KEY": key.hex()} if key is not None else {}, **(env or {}))
        argv = [sys.executable, "-m", "host.cli", "emulate", str(system),
                *(["--robot"] if robot else []), *self.keyed, *extra]
        devices = (len(yaml.safe_load((system / "robot.yaml").read_text())["devices"])
                   if robot else 0)
        names = ("board", "control", *(["world"] if "--world" in extra else []))
        urls = len(names) + sum(o in FRONT_ENDS for o in extra)

        def up(c: Child) -> bool:
            return (len(c.devices()) == devices and all(n in c.urls() for n in names)
                    and len(c.urls()) >= urls)

        for _ in range(TRIES):  # a port its runtime picked was taken meanwhile: start again
            self.child = Child(argv, cwd=ROOT, env=self.env, name="dxboard emulate")
            try:
                if self.child.wait_ready(up, BOARD_START_S):
                    return
            except TimeoutError:
                pass
            self.stop()
            said = "\n".join([*self.child.lines[-10:], *self.child.err_tail])
            if not clashed(said):
                break
        raise AssertionError(f"dxboard emulate did not print its URLs: {said}")

    def __enter__(self) -> RunningBoard:
        return self

    def __exit__(self, *exc: object) -> None:
        self.stop()

    def board(self, *args: str) -> str:
        """``dxboard board BOARD_URL ARGS`` with its key, as an operator would; its output."""
        return _dxboard("board", self.urls["board"], *args, *self.keyed, env=self.env)

    def inject(self, channel: str, fault: str, *params: str) -> None:
        """``dxboard inject CONTROL_URL CHANNEL FAULT PARAMS``."""
        _dxboard("inject", self.urls["control"], channel, fault, *params, env=self.env)

    def stop(self) -> int:
        """SIGTERM to its group, SIGKILL if it hangs; its exit code."""
        return self.child.stop(signal.SIGTERM, STOP_GRACE_S, group=True)

    def kill(self) -> None:
        """``kill -9`` (its whole group)."""
        self.child.stop(signal.SIGKILL, STOP_GRACE_S, group=True)


def _dxboard(*args: str, env: Mapping[str, str]) -> str:
    """Run one ``dxboard`` command; its output, or AssertionError with what it said."""
    p = subprocess.run([sys.executable, "-m", "host.cli", *args], cwd=ROOT, env=env,
                       capture_output=True, text=True, timeout=MIN_WAIT_S)
    if p.returncode != 0:
        raise AssertionError(f"dxboard {args[0]} failed ({p.returncode}): {p.stderr}")
    return p.stdout


def daemon_on(tmp: Path, b: RunningBoard, system: Path, key: Path) -> RunningDaemon:
    """``dxboard run SYSTEM --board URL`` with the key file, journal in ``tmp`` (made here),
    its nodes given the board's devices (``DXBOARD_DEVICES``)."""
    tmp.mkdir()
    return RunningDaemon(tmp, system, ("--key-file", str(key)), board=b.urls["board"],
                         env={"DXBOARD_DEVICES": json.dumps(b.devices)})
