"""``dxboard plan`` knows the robot's middleware, as the daemon does (a real subprocess).

A hung Hokuyo (powered, its driver running, ``/scan`` silent) is repaired on Zenoh by a power
cycle and a restart of its driver; on ROS 2 its driver is a managed node (``lifecycle: true``)
and is reconfigured by lifecycle transitions instead (``reconfigure_node``). The middleware is
the robot's ``observers: source: kind:``, overridden by ``$DXBOARD_MIDDLEWARE`` and by
``--middleware``, exactly as for ``dxboard run``.
"""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from tests.robot.conftest import ROOT

TEDUSAR = ROOT / "models" / "tedusar"
HANG = "on(hokuyo)\nrunning(hokuyo_node)\n"  # the board and the supervisor: all looks fine
# the driver is stopped before its device's power cycle (host/planning/plan.py: stops_first)
RESTART = [("stop_node", ["hokuyo_node"]), ("power_cycle", ["hokuyo"]),
           ("start_node", ["hokuyo_node"])]
LIFECYCLE = [("power_cycle", ["hokuyo"]), ("reconfigure_node", ["hokuyo_node"])]


def plan(*args: str, env: dict[str, str] | None = None) -> subprocess.CompletedProcess[str]:
    environ = {k: v for k, v in os.environ.items() if k != "DXBOARD_MIDDLEWARE"}
    return subprocess.run([sys.executable, "-m", "host.cli", "plan", *args], cwd=ROOT,
                          capture_output=True, text=True, timeout=120,
                          env={**environ, **(env or {})})


def steps(*args: str, env: dict[str, str] | None = None) -> list[tuple[str, list[str]]]:
    out = plan(*args, "--json", env=env)
    assert out.returncode == 0, out.stderr
    return [(s["action"], s["args"]) for s in json.loads(out.stdout)["plan"]]


@pytest.fixture
def hang(tmp_path: Path) -> Path:
    obs = tmp_path / "hang.txt"
    obs.write_text(HANG)
    return obs


@pytest.fixture
def ros_robot(tmp_path: Path) -> Path:
    """``models/tedusar`` whose one setting says ROS 2."""
    d = tmp_path / "tedusar"
    shutil.copytree(TEDUSAR, d)
    text = (d / "system.yaml").read_text()
    (d / "system.yaml").write_text(text.replace("observers:\n",
                                                "observers:\n  source: {kind: ros2}\n", 1))
    return d


def test_the_robots_middleware_decides_how_a_managed_driver_is_repaired(
        hang: Path, ros_robot: Path) -> None:
    obs = ("--bad", "hokuyo", "--obs", str(hang))
    assert steps(str(TEDUSAR), *obs) == RESTART  # the model says zenoh
    assert steps(str(ros_robot), *obs) == LIFECYCLE  # the model says ros2
    # overridden as for dxboard run: the option, else $DXBOARD_MIDDLEWARE
    assert steps(str(TEDUSAR), *obs, "--middleware", "ros2") == LIFECYCLE
    assert steps(str(ros_robot), *obs, "--middleware", "zenoh") == RESTART
    assert steps(str(TEDUSAR), *obs, env={"DXBOARD_MIDDLEWARE": "ros2"}) == LIFECYCLE
    assert steps(str(ros_robot), *obs, "--middleware", "zenoh",
                 env={"DXBOARD_MIDDLEWARE": "ros2"}) == RESTART
    # a driver found abnormal by itself is restarted, lifecycle or not
    assert [a for a, _ in steps(str(ros_robot), "--bad", "hokuyo_node", "--obs", str(hang))] \
        == ["stop_node", "start_node"]
    text = plan(str(ros_robot), *obs).stdout  # and for a person
    assert "1. power_cycle(hokuyo)" in text and "2. reconfigure_node(hokuyo_node)" in text


@pytest.mark.parametrize(("args", "env", "message"), [
    (("--middleware", "dds"), {}, "invalid choice: 'dds'"),
    ((), {"DXBOARD_MIDDLEWARE": "dds"}, "DXBOARD_MIDDLEWARE=dds: not a middleware"),
])
def test_a_bad_middleware_is_one_line_with_exit_2(
        args: tuple[str, ...], env: dict[str, str], message: str) -> None:
    out = plan(str(TEDUSAR), "--bad", "hokuyo", *args, env=env)
    assert out.returncode == 2 and message in out.stderr
    assert "Traceback" not in out.stderr and out.stdout == ""


def test_middleware_is_for_a_robot_directory(tmp_path: Path) -> None:
    from tests.diagnosis.originals import JAGUAR_2012  # a tug model file of the original

    out = plan(str(JAGUAR_2012), "--bad", "jaguar", "--middleware", "ros2")
    assert out.returncode == 2 and "--middleware is for a robot directory" in out.stderr
    assert len(out.stderr.strip().splitlines()) == 1


def test_help_names_the_option() -> None:
    out = plan("--help")
    assert out.returncode == 0 and "--middleware {zenoh,ros2}" in out.stdout
    assert "reconfigure_node" in out.stdout
