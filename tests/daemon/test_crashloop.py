"""End to end: a driver that exits at once because its device is off is diagnosed as the
device, and is neither restarted in a loop nor quarantined for the device's fault (issue 28,
item 1).

``dxboard run --emulate`` on a copy of the fast TEDUSAR robot whose thermal camera driver
behaves as real drivers do (usb_cam): it exits 1 when it loses its camera, or cannot reach it
within a second of its start (``emulator/robot/node.py --exit-without-device``), instead of
waiting for it. Each test has a daemon of its own, started healthy (the attempts a test
spends and the driver's runs are history the next test must not inherit), and ends with the
robot healthy again.

First, a person switches the camera off on the board (``dxboard board off``): the daemon holds
it (no repair undoes a deliberate switch-off), and the driver exits. Each restart of the
driver dies at once. The test proves, from the daemon's journal and JSON API, that

1. once the camera is seen off, every diagnosis that blames the driver blames the camera with
   it, never the driver alone;
2. the driver is started at most 3 times, no more over several further diagnoses, and is not
   quarantined: the daemon says it waits for the camera (``host.repair.crashloop``);
3. once the person switches the camera on again, the driver is started and the robot is
   healthy, the camera's images back.

Without the crash-loop handling (``RepairService._blame_devices`` returning the diagnosis as
it is) the driver is restarted three times and quarantined: the test fails on (2).

Second, the camera's switch fails off (``dxboard inject thermal_camera stuck_off``: the board
faults the channel, the camera loses its power, its driver exits). The camera's power-ups fail
and it is quarantined; the test proves the same (1) and (2): the driver is not quarantined
with it. (It was, before the daemon let a dead device's driver wait, ``host.repair.crashloop``:
restarted once the camera was quarantined, it died at once, and its attempts, spent with the
camera's, quarantined it too.) Once the switch works again, a person clears the camera (one
command, as docs/troubleshooting-quarantine.md says) and the robot is healthy.
"""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest

from host.events import describe
from host.journal import ActionRecord, DiagnosisRecord, Observation
from host.launch.running import healthy_robot
from tests.daemon.runner import KEY, RunningDaemon, fast_copy, healthy, last_id

HEAL_S = 90.0
QUARANTINE_S = 150.0
DEVICE, DRIVER = "thermal_camera", "thermal_camera_node"
MAX_STARTS = 3


def exiting_copy(tmp: Path) -> Path:
    """The fast TEDUSAR robot whose thermal camera driver exits without its camera."""
    system = fast_copy(tmp)
    path = system / "system.yaml"
    text = path.read_text()
    shipped = f"command: [python, -m, emulator.robot.node, {DRIVER}]"
    assert text.count(shipped) == 1, "the shipped model's driver command changed"
    path.write_text(text.replace(
        shipped, f"command: [python, -m, emulator.robot.node, {DRIVER}, --exit-without-device]"))
    return system


@pytest.fixture
def robot(tmp_path: Path) -> Iterator[tuple[RunningDaemon, Path]]:
    """A daemon of the test's own, once its robot is healthy, and the board's key file."""
    with healthy_robot(tmp_path, exiting_copy(tmp_path), KEY, HEAL_S) as d:
        yield d, tmp_path / "key"


def actions(d: RunningDaemon, mark: int) -> list[ActionRecord]:
    return [e.payload for e in d.journal("action")
            if e.id > mark and isinstance(e.payload, ActionRecord)]


def starts(d: RunningDaemon, mark: int) -> int:
    """The driver's starts since ``mark`` (each start_node step's first record)."""
    return len({a.action_id for a in actions(d, mark)
                if a.action == "start_node" and tuple(a.args) == (DRIVER,)})


def diagnoses(d: RunningDaemon, mark: int) -> list[set[str]]:
    """The candidate diagnoses since the camera was first seen off after ``mark`` (before, a
    driver that lost its camera may die before the board's reading of the camera arrives)."""
    off = min((e.id for e in d.journal("observation") if e.id > mark
               and isinstance(e.payload, Observation)
               and e.payload.literal == f"on({DEVICE})" and e.payload.value is False),
              default=None)
    assert off is not None, f"on({DEVICE}) = false never observed"
    return [set(bad) for e in d.journal("diagnosis") if e.id > off
            and isinstance(e.payload, DiagnosisRecord) for bad in e.payload.diagnoses]


def said(d: RunningDaemon, mark: int) -> list[str]:
    return [describe(e.payload) for e in d.journal(("note", "repair", "quarantine"))
            if e.id > mark]


def all_finished(d: RunningDaemon, mark: int) -> bool:
    acts = actions(d, mark)
    return {a.action_id for a in acts if str(a.state) == "started"} <= {
        a.action_id for a in acts if a.finished is not None}


def waits_for_its_device(d: RunningDaemon, mark: int) -> tuple[int, dict[str, Any]]:
    """(2) and (1) of the module: once the started actions have ended, the driver is not
    started again over two further windows, is not quarantined, and the daemon says it waits
    for the camera; every diagnosis that blames the driver blames the camera with it. The
    driver's starts since ``mark``, and the daemon's status."""
    d.wait_journal(lambda: all_finished(d, mark), 30, "the started actions' results")
    d.settled(10.0, runs=4)  # the daemon had its chances to start the driver again
    count = starts(d, mark)
    d.settled(10.0, runs=4)
    d.caught_up()
    st = d.status()
    assert DRIVER not in st["quarantined"], st["quarantined"]
    assert starts(d, mark) == count, "the driver is still restarted"
    assert count <= MAX_STARTS, f"{count} starts of {DRIVER}"
    assert any(f"{DRIVER} is not restarted until {DEVICE} is back" in t
               for t in said(d, mark)), said(d, mark)
    found = diagnoses(d, mark)  # the camera is the fault, the driver never alone
    assert any(DEVICE in bad for bad in found), found
    assert not [bad for bad in found if DRIVER in bad and DEVICE not in bad], found
    return count, st


def test_a_driver_that_dies_without_its_device_switched_off_waits_for_it(
        robot: tuple[RunningDaemon, Path]) -> None:
    d, key = robot
    d.wait_for(healthy, HEAL_S, "healthy")
    mark = last_id(d)
    d.board("off", DEVICE, key_file=key)  # a person switches the camera off on purpose
    d.wait_for(lambda s: DEVICE in s["held"], 15, "the camera held")
    # its driver loses the camera and exits; each restart dies at once: the daemon sees the
    # loop and waits for the camera (or, what this test exists to catch, quarantines the
    # driver after its attempts)
    d.wait_journal(lambda: DRIVER in d.status()["quarantined"] or any(
        f"{DRIVER} is not restarted until {DEVICE} is back" in t for t in said(d, mark)),
        QUARANTINE_S, "the loop seen, or the driver quarantined")
    count, st = waits_for_its_device(d, mark)
    assert count >= 1 and st["observations"].get(f"running({DRIVER})") is False
    assert st["observations"]["ok(/odom)"] is True  # the rest of the robot keeps running
    # the person switches the camera on again: its driver is started, the robot healthy
    d.board("on", DEVICE, key_file=key)
    st = d.wait_for(lambda s: healthy(s) and s["observations"].get("ok(/thermal/image)") is True
                    and not s["held"], HEAL_S, "the robot healthy with its camera back")
    assert st["observations"][f"running({DRIVER})"] is True
    assert not st["quarantined"]



def test_a_driver_that_dies_with_its_switch_stuck_off_is_not_quarantined_with_it(
        robot: tuple[RunningDaemon, Path]) -> None:
    d, _ = robot
    d.wait_for(healthy, HEAL_S, "healthy")
    mark = last_id(d)
    d.inject(DEVICE, "stuck_off")  # the camera's switch fails off: its driver exits
    d.wait_journal(lambda: any(t.startswith(f"quarantined {DEVICE}") for t in said(d, mark)),
                   QUARANTINE_S, f"{DEVICE} quarantined")
    _, st = waits_for_its_device(d, mark)
    assert st["observations"]["ok(/odom)"] is True  # the rest of the robot keeps running
    # the switch is replaced; a person clears the camera (one command): the robot comes back
    d.inject("clear")
    answer = d.operator("quarantine", "clear", DEVICE)
    assert answer.startswith(f"{DEVICE}: quarantine cleared"), answer
    st = d.wait_for(lambda s: healthy(s) and s["observations"].get("ok(/thermal/image)") is True,
                    HEAL_S, "the robot healthy with its camera back")
    assert st["observations"][f"running({DRIVER})"] is True
    assert not st["quarantined"]
