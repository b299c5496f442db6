"""``dxboard run --emulate`` on the virtual TEDUSAR robot: it brings the robot up by itself,
then each fault is injected with ``dxboard inject`` (or, for the paper's device shut-down,
an operator's ``dxboard board off``) and the daemon must diagnose it, repair what a repair
can help, verify the repair, and leave alone what it cannot (quarantine, link loss).

One daemon serves the whole module, in order: every test starts and ends with a healthy
robot, except the last, which quarantines a permanently hung device. Device boot times are
shortened (``fast_copy``); everything else is the real model, processes and sockets.

The faults whose path depends on the robot's middleware run on both (``middleware``: one
daemon per middleware, the ROS 2 one on a DDS domain of its own): the power-up (every node
started and verified through its topics), a hung lidar (power cycle, then its driver restarted
on Zenoh, reconfigured by lifecycle transitions on ROS 2: a managed node), an overcurrent trip
(the board's own protection, the device's topics back) and a crashed driver (its process
exits: restarted). The device shut down by a person, the link loss and the permanent hang go
through the board, the operator socket and the quarantine alone, the same on either
middleware: they run on Zenoh only, so the ROS 2 robot costs one more power-up and three
faults, not the module twice.
"""

from __future__ import annotations

import contextlib
import os
import signal
from collections.abc import Iterator
from pathlib import Path

import psutil
import pytest

from host.events import describe
from host.journal import ActionRecord, DiagnosisRecord, Observation, PlanRecord
from tests.daemon.runner import (
    RunningDaemon,
    bad_sets,
    fast_copy,
    healthy,
    key_file,
    last_id,
    node_processes,
)
from tests.ros.domain import claim_domain, domain_env

ROBOT = {"jaguar", "hokuyo", "laser_alignment", "jaguar_node", "hokuyo_node",
         "laser_alignment_node", "imu_node", "joy_node", "jaguar_teleop_node", "hector_mapping",
         "laser_alignment_control",
         "thermal_camera", "thermal_camera_node"}  # the camera: beyond paper 000's 11
HEAL_S = 60.0


ZENOH_ONLY = pytest.mark.parametrize("middleware", ["zenoh"], indirect=True)


@pytest.fixture(scope="module", params=["zenoh", "ros2"])
def middleware(request: pytest.FixtureRequest) -> str:
    """The robot's middleware (``dxboard run --middleware``)."""
    return str(request.param)


@pytest.fixture(scope="module")
def robot(tmp_path_factory: pytest.TempPathFactory,
          middleware: str) -> Iterator[tuple[RunningDaemon, Path]]:
    tmp = tmp_path_factory.mktemp(f"repairs-{middleware}")
    key = key_file(tmp)
    with contextlib.ExitStack() as stack:
        env = (domain_env(stack.enter_context(claim_domain())) if middleware == "ros2"
               else {})
        d = RunningDaemon(tmp, fast_copy(tmp), env=env, extra_args=(
            "--key-file", str(key), "--middleware", middleware))
        stack.callback(d.close)
        yield d, key



def actions_since(d: RunningDaemon, after: int) -> list[ActionRecord]:
    return [e.payload for e in d.journal("action")
            if e.id > after and isinstance(e.payload, ActionRecord)]


def finished(records: list[ActionRecord]) -> list[tuple[str, tuple[str, ...], str]]:
    return [(r.action, tuple(r.args), str(r.state)) for r in records if r.finished is not None]


def said_since(d: RunningDaemon, mark: int) -> list[str]:
    """What the daemon journalled since ``mark`` (actions, notes, diagnoses): for a failure's
    message, so that a run that fails once says why."""
    return [describe(e.payload) for e in d.journal(("action", "note", "diagnosis"))
            if e.id > mark][:40]


def healthy_after(d: RunningDaemon, mark: int,
                  action: str) -> list[tuple[str, tuple[str, ...], str]]:
    """The actions finished since ``mark``, once the robot is healthy after an ``action``."""
    d.wait_for(lambda s: healthy(s) and any(
        a == action for a, _, _ in finished(actions_since(d, mark))), HEAL_S,
        f"healthy after a {action}")
    d.caught_up()
    return finished(actions_since(d, mark))



def test_power_up_brings_the_whole_robot_up(robot: tuple[RunningDaemon, Path],
                                            middleware: str) -> None:
    d, _ = robot
    st = d.wait_for(healthy, HEAL_S, "the robot powered up and healthy")
    d.caught_up()
    # the nodes it started speak the middleware it was told (`dxboard run --middleware`)
    nodes = node_processes(d.system_dir)
    assert len(nodes) == 9
    for pids in nodes.values():
        env = psutil.Process(pids[0]).environ()
        assert env["DXBOARD_MIDDLEWARE"] == middleware
        if middleware == "ros2":
            assert env["ROS_DOMAIN_ID"] == d.env["ROS_DOMAIN_ID"]
    assert all(st["observations"][f"running({n})"] for n in
               ("jaguar_node", "hokuyo_node", "imu_node", "hector_mapping"))
    assert st["observations"]["ok(/scan)"] and st["observations"]["ok(/map)"]
    first = next(p.payload for p in d.journal("diagnosis")
                 if isinstance(p.payload, DiagnosisRecord) and p.payload.diagnoses
                 and p.payload.diagnoses[0])
    assert set(first.diagnoses[0]) <= ROBOT  # the paper's power-up: all abnormal
    done = finished(actions_since(d, 0))
    assert all(state == "succeeded" for _, _, state in done)
    acts = [(a, args[0]) for a, args, _ in done]
    for dev in ("jaguar", "hokuyo", "laser_alignment"):
        assert ("power_up", dev) in acts
    # hardware is switched on before its driver starts (which then retries while the device
    # boots: it does not wait for the power-up to be verified)
    records = actions_since(d, 0)
    up_start = {r.args[0]: r.started for r in records if r.action == "power_up"}
    node_start = {r.args[0]: r.started for r in records if r.action == "start_node"}
    for dev, node in (("jaguar", "jaguar_node"), ("hokuyo", "hokuyo_node")):
        assert node_start[node] >= up_start[dev]


@ZENOH_ONLY
def test_device_shut_down_by_a_person_is_held_then_repaired_as_in_the_paper(
        robot: tuple[RunningDaemon, Path]) -> None:
    d, key = robot
    d.wait_for(healthy, HEAL_S, "healthy")
    mark = last_id(d)
    d.board("off", "jaguar", key_file=key)  # a person switches the base off on purpose
    st = d.wait_for(lambda s: "jaguar" in s["held"], 15, "the base held")
    assert "switched off on the board" in st["held"]["jaguar"]
    assert d.operator("hold", "list") == f"jaguar: {st['held']['jaguar']}"
    d.wait_for(lambda s: any("jaguar" in b for b in bad_sets(s)), 15, "jaguar diagnosed")
    d.settled(3.0)  # the daemon had its chance to repair it: it may not
    assert not actions_since(d, mark)
    assert d.status()["observations"].get("on(jaguar)") is False  # still off
    # released, the daemon repairs it as in paper 000 §VI-B
    assert d.operator("hold", "release", "jaguar") == "jaguar released"
    d.wait_for(lambda s: healthy(s) and len(actions_since(d, mark)) >= 6, HEAL_S,
               "jaguar repaired")
    d.caught_up()
    done = finished(actions_since(d, mark))
    assert done == [("power_up", ("jaguar",), "succeeded"),
                    ("stop_node", ("jaguar_node",), "succeeded"),
                    ("start_node", ("jaguar_node",), "succeeded")]
    assert not d.status()["held"]


def test_a_hung_lidar_is_power_cycled_and_its_driver_restarted_or_reconfigured(
        robot: tuple[RunningDaemon, Path], middleware: str) -> None:
    d, _ = robot
    d.wait_for(healthy, HEAL_S, "healthy")
    mark = last_id(d)
    d.inject("hokuyo", "hang")
    done = healthy_after(d, mark, "power_cycle")
    # /scan stopped while the lidar's current stayed in its band: found through the topic
    # (read off the journal: a confirmed silence is repaired at once, so the power cycle may
    # switch the lidar off before a look at the status would see the silence)
    seen: dict[str, bool | None] = {}
    for e in d.journal("observation"):
        if e.id > mark and isinstance(e.payload, Observation):
            if e.payload.literal == "ok(/scan)" and e.payload.value is False:
                break
            seen[e.payload.literal] = e.payload.value
    else:
        raise AssertionError("no ~ok(/scan) in the journal")
    assert seen.get("in_band(hokuyo)", True) is True and seen.get("on(hokuyo)", True) is True
    assert ("power_cycle", ("hokuyo",), "succeeded") in done
    if middleware == "ros2":  # a managed node: the same process, a fresh connection
        assert ("reconfigure_node", ("hokuyo_node",), "succeeded") in done
        assert not any(a in ("stop_node", "start_node") and args == ("hokuyo_node",)
                       for a, args, _ in done)  # (another node may flap meanwhile on a
        # loaded machine and be restarted: not asserted on)
    else:
        assert ("start_node", ("hokuyo_node",), "succeeded") in done


def test_an_overcurrent_trip_is_diagnosed_and_the_device_restored(
        robot: tuple[RunningDaemon, Path]) -> None:
    d, _ = robot
    d.wait_for(healthy, HEAL_S, "healthy")
    mark = last_id(d)
    # twice its 1 A rating: the thermal model trips it in about a second, the board retries
    # after 1, 2 and 5 s before it latches, time enough to clear the fault on a loaded
    # machine (a short, 5x, latches on its one retry after 1 s: a race with `dxboard inject`
    # that a loaded machine loses, and then the daemon rightly quarantines the device)
    d.inject("laser_alignment", "overcurrent", "amps=2")
    d.wait_for(lambda s: any("laser_alignment" in b for b in bad_sets(s)), 10,
               "laser_alignment diagnosed")
    d.inject("clear")
    d.wait_for(healthy, HEAL_S, "healthy again")
    d.caught_up()
    tripped = [e.payload for e in d.journal("observation") if e.id > mark
               and isinstance(e.payload, Observation)
               and e.payload.literal == "tripped(laser_alignment)" and e.payload.value]
    assert tripped, "the trip was observed"


def test_a_crashed_driver_is_restarted(robot: tuple[RunningDaemon, Path]) -> None:
    d, _ = robot
    d.wait_for(healthy, HEAL_S, "healthy")
    mark = last_id(d)
    [pid] = node_processes(d.system_dir)["jaguar_node"]
    os.kill(pid, signal.SIGKILL)  # the driver dies (a segfault, the OOM killer)
    d.wait_for(lambda s: s["observations"].get("running(jaguar_node)") is False, 30,
               "the driver seen gone")
    done = healthy_after(d, mark, "start_node")
    # the driver is restarted, its device (powered and well) left alone (another topic may
    # flap meanwhile on a loaded machine and have its own node restarted: not asserted on)
    assert ("start_node", ("jaguar_node",), "succeeded") in done
    assert [a for a, args, _ in done if {"jaguar", "jaguar_node"} & set(args)] == [
        "start_node"], (done, said_since(d, mark))  # the states, and the daemon's words
    [new] = node_processes(d.system_dir)["jaguar_node"]
    assert new != pid
    assert d.status()["observations"]["ok(/odom)"] is True


@ZENOH_ONLY
def test_link_loss_is_blamed_on_the_link_and_nothing_is_switched(
        robot: tuple[RunningDaemon, Path]) -> None:
    d, _ = robot
    d.wait_for(healthy, HEAL_S, "healthy")
    mark = last_id(d)
    d.inject("board", "link_disconnect")
    st = d.wait_for(lambda s: bad_sets(s) == [{"board"}], 15, "the link diagnosed")
    assert st["observations"].get("on(hokuyo)") is None  # unknown, not false
    d.settled(2.0)  # a repair would have started by now
    assert not actions_since(d, mark)
    d.inject("clear")
    d.wait_for(lambda s: s["board_link_up"] and not s["diagnoses"], 30, "the link back")
    d.caught_up()
    assert not actions_since(d, mark)
    notes = [describe(e.payload) for e in d.journal("note") if e.id > mark]
    assert any("link is down" in t for t in notes) or not any(
        isinstance(e.payload, PlanRecord) for e in d.journal("plan") if e.id > mark)


@ZENOH_ONLY
def test_a_permanent_hang_is_quarantined_and_the_rest_keeps_running(
        robot: tuple[RunningDaemon, Path]) -> None:
    d, _ = robot
    d.wait_for(healthy, HEAL_S, "healthy")
    mark = last_id(d)
    d.inject("hokuyo", "hang", "permanent=true")
    d.wait_journal(lambda: any(describe(e.payload).startswith("quarantined")
                               for e in d.journal("quarantine") if e.id > mark),
                   120, "a quarantine")
    cycles = [r for r in actions_since(d, mark)
              if r.action == "power_cycle" and r.finished is not None]
    assert 1 <= len(cycles) <= 3  # bounded: at most 3 attempts, then quarantine
    d.settled(3.0)
    count = len(actions_since(d, mark))
    d.settled(3.0)
    assert len(actions_since(d, mark)) == count  # no loop of repairs
    st = d.status()
    assert st["observations"]["ok(/odom)"] is True  # the base still works
    assert st["observations"]["ok(/imu_data)"] is True
    # the hung lidar is what is quarantined (not the driver that was restarted on the way),
    # and it is switched off
    assert "hokuyo" in st["quarantined"], st["quarantined"]
    assert st["observations"].get("on(hokuyo)") is False
    # issue 25 item 9: a person fixes the lidar and clears the device, one command as
    # docs/troubleshooting-quarantine.md says; what was quarantined with it (its driver) is
    # cleared too, and said; the robot comes back
    assert "hokuyo" in d.operator("quarantine", "list")
    with_it = sorted(set(st["quarantined"]) - {"hokuyo"})
    d.inject("clear")
    said = d.operator("quarantine", "clear", "hokuyo")
    assert said.startswith("hokuyo: quarantine cleared"), said
    for driver in with_it:
        assert driver in said, said
    st = d.wait_for(lambda s: healthy(s) and s["observations"].get("ok(/scan)") is True,
                    HEAL_S, "the robot back after one clear")
    assert not st["quarantined"]
