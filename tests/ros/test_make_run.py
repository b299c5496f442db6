"""``make run`` runs the ROS 2 robot by default, ``DXBOARD_MIDDLEWARE=zenoh make run`` Zenoh.

Read off ``make -n run`` (what make would run, nothing started): the daemon's command line
names the middleware, so the daemon, its planner and the nodes it starts all use it
(``dxboard run --middleware``; the nodes' environment is checked end to end in
``tests/daemon/test_repairs.py``).
"""

from __future__ import annotations

import os
import subprocess

import pytest

from tests.robot.conftest import ROOT


def dry_run(**env: str) -> str:
    environ = {k: v for k, v in os.environ.items()
               if k not in ("DXBOARD_MIDDLEWARE", "MAKEFLAGS", "MAKELEVEL")}
    out = subprocess.run(["make", "-n", "run"], cwd=ROOT, capture_output=True, text=True,
                         timeout=60, env={**environ, **env})
    assert out.returncode == 0, out.stderr
    return out.stdout.replace("\\\n", " ")


@pytest.mark.parametrize(("env", "middleware"), [({}, "ros2"),
                                                  ({"DXBOARD_MIDDLEWARE": "zenoh"}, "zenoh"),
                                                  ({"DXBOARD_MIDDLEWARE": "ros2"}, "ros2")])
def test_make_run_picks_the_middleware(env: dict[str, str], middleware: str) -> None:
    line = next(x for x in dry_run(**env).splitlines() if " run models/tedusar " in x)
    assert f"--middleware {middleware} " in " ".join(line.split()) + " "
    assert "--emulate" in line and "--control 127.0.0.1:7001" in line
