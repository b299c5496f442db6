"""``dxboard run --emulate`` end to end, on what the board alone shows: startup, the power-up
diagnosis, a lost board link, and a clean stop. (Repairs: test_repairs.py.)"""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path

import pytest

from host.journal import BoardEvent, DiagnosisRecord, LinkChange, Note, Observation, RunStarted
from tests.daemon.runner import RunningDaemon, bad_sets

PAPER_11 = {
    "jaguar", "hokuyo", "laser_alignment", "laser_alignment_node", "laser_alignment_control",
    "hector_mapping", "jaguar_node", "hokuyo_node", "imu_node", "jaguar_teleop_node", "joy_node",
}
# the robot's model adds the thermal camera and its driver (the missions' victim detection),
# beyond paper 000's 11: off at power-up too
PAPER_POWER_UP = PAPER_11 | {"thermal_camera", "thermal_camera_node"}


@pytest.fixture
def daemon(tmp_path: Path) -> Iterator[RunningDaemon]:
    d = RunningDaemon(tmp_path, extra_args=("--dry-run",))
    try:
        yield d
    finally:
        d.close()


def test_it_starts_sees_the_board_and_diagnoses_the_power_up(daemon: RunningDaemon) -> None:
    assert daemon.urls["board"].startswith("tcp://127.0.0.1:")
    assert daemon.urls["control"].startswith("control://127.0.0.1:")
    st = daemon.wait_for(lambda s: s["board_link_up"] and bad_sets(s) == [PAPER_POWER_UP],
                         label="the power-up diagnosis")
    names = [c["name"] for c in st["channels"]]
    assert names[:8] == ["sensor_head", "laser_alignment", "pc", "hokuyo", "kinect", "router",
                         "thermal_camera", "jaguar"]
    assert st["board_link_up"] is True
    assert st["channels"][2]["on"] is True  # the PC, powered at power-up
    # paper 000 §VI-A: every device and node of the robot is abnormal, nothing else
    assert st["diagnosis_complete"] is True
    assert st["observations"]["on(jaguar)"] is False
    assert st["observations"]["link(board)"] is True


def test_a_lost_link_is_diagnosed_as_the_link(daemon: RunningDaemon) -> None:
    daemon.wait_for(lambda s: bad_sets(s) == [PAPER_POWER_UP], label="the power-up diagnosis")
    daemon.inject("board", "link_disconnect")
    # the devices drop out of the diagnosis (only the board could tell their state), the
    # board's link comes in; the nodes the host sees itself are still not running
    devices = {"jaguar", "hokuyo", "laser_alignment", "thermal_camera"}
    expected = (PAPER_POWER_UP - devices) | {"board"}
    st = daemon.wait_for(lambda s: bad_sets(s) == [expected], label="the link diagnosis")
    assert st["board_link_up"] is False
    # what only the board could tell is unknown now, not false
    for atom in ("on(jaguar)", "on(hokuyo)", "tripped(jaguar)"):
        assert st["observations"].get(atom) is None, atom
    daemon.inject("clear")
    daemon.wait_for(lambda s: bad_sets(s) == [PAPER_POWER_UP] and s["board_link_up"],
                    timeout=30, label="the link back")


def test_ctrl_c_stops_cleanly_and_the_journal_holds_every_step(daemon: RunningDaemon) -> None:
    daemon.wait_for(lambda s: s["board_link_up"] and bad_sets(s) == [PAPER_POWER_UP],
                    label="the power-up diagnosis")
    assert daemon.interrupt() == 0
    daemon.close()  # its terminal read to the end
    assert any(line.endswith(" stopping") for line in daemon.lines)  # said on Ctrl-C
    entries = daemon.journal()
    payloads = [e.payload for e in entries]
    first = payloads[0]  # the run begins with its id (host.journal.runs)
    assert isinstance(first, RunStarted) and first.robot == "tedusar" and first.dry_run
    assert first.board == daemon.urls["board"]
    assert isinstance(payloads[-1], Note) and "stopped" in payloads[-1].text
    assert any(isinstance(p, BoardEvent) and p.event == "connected" for p in payloads)
    diagnoses = [p for p in payloads if isinstance(p, DiagnosisRecord)]
    assert diagnoses and set(diagnoses[-1].diagnoses[0]) == PAPER_POWER_UP
    changes = [(p.literal, p.value) for p in payloads if isinstance(p, Observation)]
    assert ("on(jaguar)", False) in changes and ("running(hokuyo_node)", False) in changes
    # on the way out every observer retracts what it said: the last word on each is unknown
    last = dict(changes)
    assert last["on(jaguar)"] is None and last["link(board)"] is None
    ids = [e.id for e in entries]
    assert ids == sorted(ids) and len(set(ids)) == len(ids)


def test_ctrl_c_on_its_terminal_stops_the_nodes_and_the_board_in_order(
        daemon: RunningDaemon) -> None:
    """The terminal signals the daemon's whole process group: the emulated board is not in
    it, so the daemon stops it last, as it does its nodes, and the board's link is not lost
    before the daemon stopped (it used to be, on every Ctrl-C of ``make run``)."""
    daemon.wait_for(lambda s: s["board_link_up"] and bad_sets(s) == [PAPER_POWER_UP],
                    label="the power-up diagnosis")
    assert daemon.ctrl_c() == 0
    payloads = [e.payload for e in daemon.journal()]
    assert isinstance(payloads[-1], Note) and "stopped" in payloads[-1].text
    assert [p.up for p in payloads if isinstance(p, LinkChange)] == [True]
    assert "link lost" not in daemon.err_path.read_text()
