"""Nodes started elsewhere (``external:``): planned like every other repair, restarted through
the actuator the model names, "not repairable here" when it names none (issue 28, items 1-2).

Before ``external:``, a node dxboard had not started could only be stopped and started as a
process of its own (``start_node``), which it cannot do for a node ``ros2 launch``, systemd or
a container runs; a standard lifecycle node was never brought up. The robot here is a copy of
the TEDUSAR model whose laser driver and mapper are managed nodes started elsewhere, rviz a
node a command restarts, the joystick watched only. The ``command`` actuator is run against a
real process the test started itself, as a launcher would.
"""

from __future__ import annotations

import asyncio
import os
import shutil
import signal
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest

from host.diagnosis.logic import parse_literal
from host.errors import UserError
from host.planning.errors import NoPlanError
from host.repair.actuators import ActuationError, Refused
from host.repair.external import ExternalNode, load_external
from host.repair.planner import RepairPlanner
from host.repair.restart import RestartActuator
from tests.robot.conftest import DXBOARD, TEDUSAR
from tests.wait import wait_until

EXTERNAL = """
external:
  hokuyo_node: {lifecycle: true}
  hector_mapping: {lifecycle: true}
  rviz: {command: [/bin/true]}
  joy_node: {}
"""


def external_robot(tmp: Path, section: str = EXTERNAL) -> Path:
    d = tmp / "robot"
    shutil.copytree(TEDUSAR, d)
    f = d / "system.yaml"
    started_elsewhere = ("hokuyo_node", "hector_mapping", "joy_node", "rviz")
    lines = [x for x in f.read_text().splitlines()
             if not any(x.startswith(f"  {n}: {{command") for n in started_elsewhere)]
    text = "\n".join(lines).replace("source: {kind: zenoh", "source: {kind: ros2")
    for n in started_elsewhere:
        text = text.replace(f"    {n}: {{supervised: true}}", f"    {n}: {{graph: true}}")
    f.write_text(text + "\n" + textwrap.dedent(section))
    return d


def steps(planner: RepairPlanner, bad: str, *obs: str) -> list[tuple[str, set[str]]]:
    plan = planner.plan(bad.split(","), [parse_literal(o) for o in obs])
    return [(str(s), {str(plan.steps[i]) for i in plan.after[s.id]}) for s in plan.steps]


def test_managed_nodes_started_elsewhere_are_brought_up_in_dependency_order(
        tmp_path: Path) -> None:
    planner = RepairPlanner.for_system(external_robot(tmp_path))
    # the mapper reads the laser's /scan: activated after it, never start_node
    assert steps(planner, "hokuyo_node,hector_mapping", "~running(hokuyo_node)",
                 "~running(hector_mapping)") == [
        ("activate_node(hokuyo_node)", set()),
        ("activate_node(hector_mapping)", {"activate_node(hokuyo_node)"})]
    # an abnormal active one is reset through its transitions, not stopped and started
    assert steps(planner, "hokuyo_node", "running(hokuyo_node)") == \
        [("reset_node(hokuyo_node)", set())]
    # its device off: powered first, then the driver brought up
    assert [s for s, _ in steps(planner, "hokuyo,hokuyo_node", "~on(hokuyo)",
                                "running(hokuyo_node)")] == \
        ["power_up(hokuyo)", "reset_node(hokuyo_node)"]


def test_a_declared_order_is_kept(tmp_path: Path) -> None:
    planner = RepairPlanner.for_system(external_robot(tmp_path, EXTERNAL.replace(
        "hokuyo_node: {lifecycle: true}", "hokuyo_node: {lifecycle: true, after: [imu_node]}"
    ).replace("joy_node: {}", "joy_node: {}\n  imu_node: {lifecycle: true}")))
    assert steps(planner, "hokuyo_node,imu_node", "~running(hokuyo_node)",
                 "~running(imu_node)") == [
        ("activate_node(imu_node)", set()),
        ("activate_node(hokuyo_node)", {"activate_node(imu_node)"})]


def test_a_node_with_an_actuator_is_restarted_one_without_is_not_repairable_here(
        tmp_path: Path) -> None:
    robot = external_robot(tmp_path)
    planner = RepairPlanner.for_system(robot)
    assert steps(planner, "rviz") == [("restart_node(rviz)", set())]
    with pytest.raises(NoPlanError, match=r"joy_node is started elsewhere and system\.yaml "
                                          r"names no actuator for it: not repairable here"):
        planner.plan(["joy_node"])
    p = subprocess.run([DXBOARD, "plan", str(robot), "--bad", "joy_node"], capture_output=True,
                       text=True, timeout=120)
    assert p.returncode == 2 and "not repairable here" in p.stderr
    assert "Traceback" not in p.stderr and len(p.stderr.strip().splitlines()) == 1


def test_bad_external_entries_are_one_line_each_naming_the_fix(tmp_path: Path) -> None:
    robot = external_robot(tmp_path, EXTERNAL.replace(
        "rviz: {command: [/bin/true]}", "rviz: {command: [/bin/true], systemd: rviz.service}"
    ).replace("joy_node: {}", "joy_node: {lifecycle: yes-please}\n  jaguar_node: {}"))
    with pytest.raises(UserError) as err:
        load_external(robot)
    text = "\n".join(str(p) for p in err.value.problems)  # type: ignore[attr-defined]
    assert "rviz: more than one actuator (systemd, command)" in text
    assert "joy_node: lifecycle 'yes-please' is not true or false" in text
    p = subprocess.run([DXBOARD, "plan", str(robot), "--bad", "rviz"], capture_output=True,
                       text=True, timeout=120)
    assert p.returncode == 2 and "Traceback" not in p.stderr


LAUNCHER = """\
import os, signal, subprocess, sys
pidfile = sys.argv[1]
old = int(open(pidfile).read())
os.kill(old, signal.SIGTERM)
new = subprocess.Popen([sys.executable, "-c", "import time; time.sleep(600)"],
                       start_new_session=True)
open(pidfile, "w").write(str(new.pid))
"""


def alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    with open(f"/proc/{pid}/stat") as f:  # a zombie is gone
        return f.read().split(") ")[1][0] != "Z"


def test_the_command_actuator_restarts_a_process_started_outside_dxboard(
        tmp_path: Path) -> None:
    # the "launcher": the test starts the node's process itself, and a restart script that
    # replaces it, as `systemctl restart` or a launch file's respawn would
    node = subprocess.Popen([sys.executable, "-c", "import time; time.sleep(600)"])
    pidfile, script = tmp_path / "node.pid", tmp_path / "restart.py"
    pidfile.write_text(str(node.pid))
    script.write_text(LAUNCHER)
    new = 0
    try:
        act = RestartActuator({"mapper": ExternalNode(
            "mapper", kind="command", target=(sys.executable, str(script), str(pidfile)))})
        detail = asyncio.run(act.restart_node("mapper"))
        assert detail.startswith("mapper restarted by ") and str(script) in detail
        node.wait(30)  # the old process is gone
        new = int(pidfile.read_text())
        assert new != node.pid
        wait_until(lambda: alive(new), 30, "the restarted process")

        refused = RestartActuator({"mapper": ExternalNode(
            "mapper", kind="command", target=(sys.executable, "-c",
                                              "import sys; sys.exit('Access denied')"))})
        with pytest.raises(ActuationError, match=r"restart_node\(mapper\): .* refused \(exit "
                                                 r"code 1\): Access denied"):
            asyncio.run(refused.restart_node("mapper"))
        missing = RestartActuator({"detector": ExternalNode(
            "detector", kind="container", target=("detector-nonexistent",))},)
        missing_docker = {**os.environ, "PATH": str(tmp_path)}  # no docker on this PATH
        old_path = os.environ["PATH"]
        os.environ["PATH"] = missing_docker["PATH"]
        try:
            with pytest.raises(ActuationError, match=r"cannot run docker restart "
                                                     r"detector-nonexistent"):
                asyncio.run(missing.restart_node("detector"))
        finally:
            os.environ["PATH"] = old_path
        with pytest.raises(Refused, match="not repairable here"):
            asyncio.run(RestartActuator({"joy": ExternalNode("joy")}).restart_node("joy"))
    finally:
        if node.poll() is None:
            node.kill()
            node.wait(10)
        if new and alive(new):
            os.kill(new, signal.SIGKILL)
