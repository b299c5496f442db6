"""system.yaml: loading the tedusar model, validation messages (file, line, fix), clauses."""

from __future__ import annotations

from pathlib import Path

import pytest

from host.diagnosis import ComponentKind, ModelError, check_system, generate, load_system
from tests.diagnosis.conftest import TEDUSAR

GOOD = """\
robot: tiny
board: {channels: 4, protected: [2]}
components:
  lidar: {kind: SH, channel: 1, current: [0.1, 1.0]}
  lidar_node:
    kind: SN
    hardware: [lidar]
    publishes: {/scan: []}
  mapper:
    kind: N
    subscribes: [/scan]
    publishes: [/map]
"""


def write(tmp_path: Path, text: str) -> Path:
    (tmp_path / "system.yaml").write_text(text)
    return tmp_path


def test_tedusar_model_matches_the_paper() -> None:
    m = load_system(TEDUSAR)
    kinds = {k: {c.name for c in m.by_kind(k)} for k in ComponentKind}
    assert kinds[ComponentKind.HN] == {"imu_node", "joy_node"}
    # the paper's, and beyond it the missions' thermal camera with its driver
    assert kinds[ComponentKind.SH] == {"jaguar", "hokuyo", "laser_alignment", "thermal_camera"}
    assert kinds[ComponentKind.H] == {"joystick", "imu", "board"}  # the board from its section
    assert kinds[ComponentKind.SN] == {"jaguar_node", "hokuyo_node", "laser_alignment_node",
                              "thermal_camera_node"}
    assert kinds[ComponentKind.N] == {"jaguar_teleop_node", "hector_mapping", "rviz",
                             "laser_alignment_control"}
    channels = {c.name: c.channel for c in m.by_kind(ComponentKind.SH)}
    assert channels == {"jaguar": 7, "hokuyo": 3, "laser_alignment": 1, "thermal_camera": 6}
    assert m.components["jaguar_node"].hardware == ("jaguar",)
    assert {"/odom", "/scan", "/map", "/imu_data", "/cmd_vel"} <= set(m.topics())
    assert m.device_on_channel(7) is m.components["jaguar"]
    assert m.protected == {2}
    assert m.components["hokuyo"].current is not None
    assert m.board == "board"


def test_the_board_link_is_diagnosed() -> None:
    text = {str(c) for c in generate(load_system(TEDUSAR)).clauses}
    assert "~AB(board) -> link(board)" in text


def test_generated_clauses_follow_the_paper() -> None:
    text = {str(c) for c in generate(load_system(TEDUSAR)).clauses}
    assert "~AB(jaguar) -> on(jaguar)" in text  # clause 1
    assert "~AB(jaguar_node), ~AB(jaguar) -> ok(/odom)" in text  # clause 2
    assert "~AB(hector_mapping), ok(/scan) -> ok(/map)" in text  # clause 4
    assert "~AB(rviz) -> running(rviz)" in text  # clause 5
    assert "~AB(jaguar_node), ~AB(imu_node) -> matched(odom_yaw_rate,imu_yaw_rate)" in text
    assert "~AB(hokuyo), on(hokuyo) -> in_band(hokuyo)" in text
    assert "~AB(hokuyo), tripped(hokuyo) -> false" in text


def test_good_model_loads(tmp_path: Path) -> None:
    m = load_system(write(tmp_path, GOOD))
    assert m.components["mapper"].publishes == {"/map": ("/scan",)}
    assert check_system(tmp_path) == []


@pytest.mark.parametrize(
    ("old", "new", "line", "needle"),
    [
        ("hardware: [lidar]", "hardware: [lidr]", 7, "unknown component 'lidr'"),
        ("subscribes: [/scan]", "subscribes: [/scna]", 11, "/scna"),
        ("channel: 1,", "channel: 2,", 4, "protected"),
        ("channel: 1,", "channel: 9,", 4, "does not exist"),
        ("    hardware: [lidar]\n", "", 5, "has no hardware"),
        ("kind: N", "kind: X", 10, "kind 'X'"),
        ("kind: N", "kind: N\n    channel: 3", 11, "unknown key 'channel'"),
        ("[0.1, 1.0]", "[1.0, 0.1]", 4, "current band"),
        ("publishes: {/scan: []}", "publishes: {/scan: [/x]}", 8, "does not subscribe"),
        ("robot: tiny", "robot: tiny\nrobots: 2", 2, "unknown key 'robots'"),
        ("components:", "components: [", 5, "YAML syntax"),
    ],
)
def test_validation_names_file_line_and_fix(
    tmp_path: Path, old: str, new: str, line: int, needle: str
) -> None:
    assert old in GOOD
    write(tmp_path, GOOD.replace(old, new, 1))
    problems = check_system(tmp_path)
    assert problems, "expected a problem"
    hit = [p for p in problems if needle in p.message]
    assert hit, [str(p) for p in problems]
    assert hit[0].line == line and hit[0].fix and str(hit[0]).startswith(str(tmp_path))
    with pytest.raises(ModelError):
        load_system(tmp_path)


def test_channel_used_twice(tmp_path: Path) -> None:
    write(tmp_path, GOOD + "  cam: {kind: SH, channel: 1}\n")
    [problem] = check_system(tmp_path)
    assert problem.line == 13 and "channel 1 used twice" in problem.message


def test_missing_directory_is_a_problem(tmp_path: Path) -> None:
    [problem] = check_system(tmp_path / "nowhere")
    assert "cannot read" in problem.message
