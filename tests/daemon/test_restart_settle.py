"""A daemon started again after ``kill -9``, with the board still running, judges nothing
before its nodes have had their settle time (issue 25, item 7: it power-cycled the healthy
base and camera and restarted 3 nodes, their topics judged 0.48-0.71 s into the run).

A real ``dxboard emulate --robot`` board (the fast TEDUSAR copy) outlives two real
``dxboard run --board`` daemons: the first brings the robot up and is killed with SIGKILL (its
nodes die with it, ``host.lifeline``); the second must start the nodes again and nothing else —
no device power-cycled or switched, no node it started stopped again.

The finding needs a loaded machine (nodes that publish late); at a load average of 10 this test
passes on the code from before the fix too. The rule itself is tested without timing in
``tests/repair/test_booting.py``.
"""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path

import pytest

from host.launch.boards import RunningBoard, daemon_on
from tests.daemon.runner import actions_started, fast_copy, healthy, key_file, node_processes
from tests.wait import wait_until

HEAL_S = 120.0
FALSE = ("power_cycle", "power_up", "shutdown", "stop_node")


@pytest.fixture
def board(tmp_path: Path) -> Iterator[tuple[RunningBoard, Path, Path]]:
    system, key = fast_copy(tmp_path), key_file(tmp_path)
    b = RunningBoard(system, key_file=key)
    try:
        yield b, system, key
    finally:
        b.stop()


def test_a_daemon_restarted_after_kill_9_repairs_nothing(
        tmp_path: Path, board: tuple[RunningBoard, Path, Path]) -> None:
    b, system, key = board
    first = daemon_on(tmp_path / "1", b, system, key)
    try:
        first.wait_for(healthy, HEAL_S, "the robot up")
        first.kill()
    finally:
        first.close()
    wait_until(lambda: not node_processes(system), 60, "the killed daemon's nodes gone")
    second = daemon_on(tmp_path / "2", b, system, key)
    try:
        second.wait_for(healthy, HEAL_S, "the robot healthy again")
        second.settled(3.0)
        assert [a for a in actions_started(second, 0) if a.split("(")[0] in FALSE] == []
    finally:
        second.close()
