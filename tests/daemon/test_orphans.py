"""No orphans, ever (issue 25, item 3): after ``kill -9`` of the daemon, 9 ``emulator.robot.node``
processes and the emulator ran on with PPID 1. Every process ``dxboard run`` starts (the
emulated board, the robot's nodes) now dies with it (``host.lifeline``); here a real daemon
has brought the whole robot up, on zenoh and on ROS 2, and is killed with SIGKILL."""

from __future__ import annotations

import contextlib
import os
import signal
from collections.abc import Iterator
from pathlib import Path

import pytest

from benchmarks._rigs.stopper import alive, children
from tests.daemon.runner import RunningDaemon, fast_copy, key_file, node_processes
from tests.ros.domain import claim_domain, domain_env
from tests.wait import wait_until


def _all_nodes(system: Path) -> dict[str, list[int]] | None:
    nodes = node_processes(system)
    return nodes if len(nodes) == 9 else None


@pytest.fixture(params=["zenoh", "ros2"])
def env(request: pytest.FixtureRequest) -> Iterator[tuple[str, dict[str, str]]]:
    with contextlib.ExitStack() as stack:
        yield str(request.param), (domain_env(stack.enter_context(claim_domain()))
                                   if request.param == "ros2" else {})


def test_kill_9_of_the_daemon_leaves_no_process_of_it_running(
        tmp_path: Path, env: tuple[str, dict[str, str]]) -> None:
    middleware, extra_env = env
    system = fast_copy(tmp_path)
    d = RunningDaemon(tmp_path, system, env=extra_env, extra_args=(
        "--key-file", str(key_file(tmp_path)), "--middleware", middleware))
    kids: list[int] = []
    try:
        # the power-up started every node (the robot need not be healthy yet)
        nodes = wait_until(lambda: _all_nodes(system), 240, "the robot's 9 nodes running",
                           interval=0.5,
                           show=lambda: node_processes(system))
        kids = children(d.proc.pid)
        assert {p for pids in nodes.values() for p in pids} <= set(kids)
        d.kill()
        wait_until(lambda: not alive(kids), 60, "every child of the killed daemon gone",
                   show=lambda: alive(kids))
        assert not node_processes(system)
    finally:
        d.close()
        for pid in alive(kids):  # the test failed: leave nothing behind for the next one
            with contextlib.suppress(OSError):


                os.kill(pid, signal.SIGKILL)
