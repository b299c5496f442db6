"""``dxboard run --emulate`` as a real subprocess, for the daemon's end-to-end tests.

``RunningDaemon`` is the launcher's (``host.launch.running``: it starts it on free ports with a
journal in a temporary folder, reads the URLs it prints, and offers what a person would use);
here are the tests' defaults and questions around it: the fast robot copy, the fixed test key,
a healthy robot as a context manager, the node processes of a robot, the journal's marks.
"""

from __future__ import annotations

import contextlib
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import psutil

from host.events import ActionRecord, ActionState
from host.experiment.robot import fast_model
from host.launch import running
from host.launch.running import MIN_WAIT_S, ROOT, TEDUSAR, RunningDaemon, healthy

__all__ = [
    "KEY", "MIN_WAIT_S", "ROOT", "TEDUSAR", "RunningDaemon", "actions_started", "bad_sets",
    "fast_copy", "healthy", "healthy_robot", "key_file", "last_id", "node_processes",
]


def fast_copy(tmp: Path) -> Path:
    """``models/tedusar`` with short device boot times (``host.experiment.robot.fast_model``)."""
    return fast_model(TEDUSAR, tmp)


def node_processes(robot: Path) -> dict[str, list[int]]:
    """The virtual robot's node processes of this robot directory, by node."""
    out: dict[str, list[int]] = {}
    for p in psutil.process_iter(["pid", "cmdline"]):
        try:
            cmd = p.info["cmdline"] or []
            if "emulator.robot.node" not in cmd or p.status() == psutil.STATUS_ZOMBIE:
                continue
            if p.environ().get("DXBOARD_ROBOT") != str(robot.resolve()):
                continue
        except psutil.Error:
            continue
        out.setdefault(cmd[cmd.index("emulator.robot.node") + 1], []).append(p.info["pid"])
    return out


KEY = bytes(range(32))


def key_file(tmp: Path, key: bytes = KEY) -> Path:
    """A key file as ``--key-file`` wants it, with the tests' key by default."""
    return running.key_file(tmp, key)


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


def last_id(d: RunningDaemon) -> int:
    """The journal's last entry once it holds everything recorded until now (a mark)."""
    d.caught_up()
    return max((e.id for e in d.journal()), default=0)


def actions_started(d: RunningDaemon, after: int) -> list[str]:
    """The repair actions (``power_cycle(hokuyo)``) started since the journal entry ``after``."""
    return [f"{p.action}({','.join(p.args)})" for e in d.journal("action") if e.id > after
            for p in [e.payload] if isinstance(p, ActionRecord)
            and p.state == ActionState.STARTED]


def bad_sets(status: dict[str, Any]) -> list[set[str]]:
    return [set(d["bad"]) for d in status["diagnoses"]]

