"""``dxboard run --emulate`` as a real subprocess, for the daemon's end-to-end tests.

``RunningDaemon`` is the launcher's (``host.launch.running``: it starts it on free ports with a
journal in a temporary folder, reads the URLs it prints, and offers what a person would use);
with the questions around it (the node processes of a robot, the journal's marks) and the
rigs the benchmarks share (``benchmarks._rigs.robots``: the fast robot copy, the fixed key, a
healthy robot as a context manager), here under the names the tests have always used.
"""

from __future__ import annotations

from typing import Any

from benchmarks._rigs.robots import KEY, fast_copy, healthy_robot, key_file
from host.launch.running import (
    MIN_WAIT_S,
    ROOT,
    TEDUSAR,
    RunningDaemon,
    actions_started,
    healthy,
    last_id,
    node_processes,
)

__all__ = [
    "KEY", "MIN_WAIT_S", "ROOT", "TEDUSAR", "RunningDaemon", "actions_started", "bad_sets",
    "fast_copy", "healthy", "healthy_robot", "key_file", "last_id", "node_processes",
]


def bad_sets(status: dict[str, Any]) -> list[set[str]]:
    return [set(d["bad"]) for d in status["diagnoses"]]

