"""Robots for the benchmarks and the tests beside them: copies of TEDUSAR and the rigs' fixed key.

``fast_copy(tmp)`` is ``models/tedusar`` with short device boot times
(``host.experiment.robot.fast_model``); ``lite_model(dest)`` cuts such a copy down to the
switchable hardware (SH components on board channels) and the board observers: no nodes, no
topics, no processes, no ``robot.yaml`` (so no virtual devices). A daemon on it is a board
emulator plus one process, so dozens fit on a small machine; faults are injected on its
control port as on the full robot. ``KEY`` is the rigs' fixed board key (never a robot's),
``key_file(tmp)`` writes it as ``--key-file`` wants it, and ``healthy_robot(tmp)`` is the fast
robot under ``dxboard run --emulate`` once it is healthy (``host.launch.running``).
"""

from __future__ import annotations

import contextlib
import shutil
from pathlib import Path

import yaml

from host.experiment.robot import fast_model
from host.launch import running
from host.launch.running import TEDUSAR, RunningDaemon

KEY = bytes(range(32))


def fast_copy(tmp: Path) -> Path:
    """``models/tedusar`` with short device boot times, in ``tmp``."""
    return fast_model(TEDUSAR, tmp)


def key_file(tmp: Path, key: bytes = KEY) -> Path:
    """``tmp/key`` holding ``key`` as ``--key-file`` wants it."""
    return running.key_file(tmp, key)


def healthy_robot(tmp: Path, heal_s: float = 90.0) -> contextlib.AbstractContextManager[
        RunningDaemon]:
    """The fast robot under ``dxboard run --emulate`` with ``KEY``, once it is healthy."""
    return running.healthy_robot(tmp, fast_copy(tmp), KEY, heal_s)


def lite_model(dest: Path) -> Path:
    """The lite robot (see the module) in ``dest``."""
    d = fast_model(TEDUSAR, dest)
    (d / "robot.yaml").unlink()
    shutil.rmtree(d / "scenarios")  # they name the nodes this model leaves out
    system = yaml.safe_load((d / "system.yaml").read_text())
    system["robot"] = "lite"
    system["components"] = {n: c for n, c in system["components"].items() if c["kind"] == "SH"}
    system["observers"] = {"hardware": system["observers"]["hardware"]}
    system.pop("processes", None)
    system.pop("values", None)
    system.pop("related", None)
    (d / "system.yaml").write_text(yaml.safe_dump(system))
    return d
