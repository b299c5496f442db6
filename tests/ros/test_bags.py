"""Bags: ``dxboard record`` a live fault of the ROS 2 robot, ``dxboard replay`` it to the same
diagnoses, ``dxboard report`` its timeline; bad input is one line and exit code 2.

The live fault: the virtual robot's board and devices (``dxboard emulate --robot``), its Hokuyo
driver as a real rclpy node in its own process on the test's DDS domain, ``dxboard record``
(a process of its own) journaling its live diagnoses while it records; the Hokuyo hangs; the
recording stops. ``dxboard replay`` runs over the bag on the bag's clock and must journal the
same sequence of minimal diagnoses (the same bad sets, in the same order).
"""

from __future__ import annotations

import shutil
import signal
import subprocess
from pathlib import Path

from host.events import Kind
from host.journal import JournalReader
from tests.robot.conftest import DXBOARD, ROOT, TEDUSAR, Robot
from tests.ros.conftest import RosNodes
from tests.wait import wait_until

WAIT_S = 120.0


def ros2(system_dir: Path) -> Path:
    """The robot directory with its one middleware setting on ROS 2."""
    f = system_dir / "system.yaml"
    f.write_text(f.read_text().replace("observers:\n", "observers:\n  source: {kind: ros2}\n", 1))
    return system_dir


def diagnoses(journal: Path) -> list[tuple[tuple[str, ...], ...]]:
    with JournalReader(journal) as r:
        return [e.payload.diagnoses for e in r.query(kind=Kind.DIAGNOSIS)]  # type: ignore[attr-defined]


def seen(journal: Path, atom: str, value: bool) -> int:
    """How often ``atom`` was observed with ``value`` so far (0 while the file is not there)."""
    if not journal.exists():
        return 0
    with JournalReader(journal) as r:
        return sum(1 for e in r.query(kind=Kind.OBSERVATION)
                   if e.payload.literal == atom and e.payload.value is value)  # type: ignore[attr-defined]


def dxboard(*args: str, env: dict[str, str] | None = None) -> subprocess.CompletedProcess[str]:
    return subprocess.run([DXBOARD, *args], capture_output=True, text=True, env=env, cwd=ROOT,
                          timeout=WAIT_S)


def test_a_bag_recorded_from_a_live_hang_replays_to_the_same_diagnoses(
        tmp_path: Path, robot_dir: Path, robot: Robot, ros_nodes: RosNodes,
        env: dict[str, str]) -> None:
    ros2(robot_dir)
    bag, live, replayed = tmp_path / "hang", tmp_path / "live.sqlite", tmp_path / "replay.sqlite"
    robot.board("on", "hokuyo")
    ros_nodes.start("hokuyo_node")
    rec = subprocess.Popen([DXBOARD, "record", str(robot_dir), str(bag), "--journal", str(live)],
                           stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=env,
                           cwd=ROOT)
    try:
        assert rec.stdout is not None
        assert rec.stdout.readline().startswith("recording"), rec.stderr  # the journal is set up
        wait_until(lambda: seen(live, "ok(/scan)", True), WAIT_S, "/scan observed ok live",
                   show=lambda: rec.poll())
        robot.inject("hokuyo", "hang")
        wait_until(lambda: seen(live, "ok(/scan)", False), WAIT_S,
                   "/scan observed silent after the hang", show=lambda: rec.poll())
    finally:
        rec.send_signal(signal.SIGINT)
        out, err = rec.communicate(timeout=WAIT_S)
    assert rec.returncode == 0, err
    assert "wrote" in out and (bag / "metadata.yaml").is_file()
    assert list(bag.glob("*.mcap"))

    p = dxboard("replay", str(bag), str(robot_dir), "--journal", str(replayed), env=env)
    assert p.returncode == 0, p.stderr
    assert "replayed" in p.stdout

    live_d, replay_d = diagnoses(live), diagnoses(replayed)
    # the hang shows: a diagnosis naming the Hokuyo or its driver after one that did not
    names = [any({"hokuyo", "hokuyo_node"} & set(bad) for bad in d) for d in live_d]
    assert False in names and True in names[names.index(False):], live_d
    assert replay_d == live_d

    chart = tmp_path / "timeline.png"
    p = dxboard("report", str(replayed), "-o", str(chart), "--model", str(robot_dir))
    assert p.returncode == 0, p.stderr
    assert chart.stat().st_size > 1000


def test_bad_input_is_one_line_and_exit_code_2(tmp_path: Path) -> None:
    zenoh_robot = TEDUSAR
    ros_robot = ros2(Path(shutil.copytree(TEDUSAR, tmp_path / "tedusar")))
    not_a_bag = tmp_path / "notes.txt"
    not_a_bag.write_text("hello\n")
    bag_dir = tmp_path / "empty"
    bag_dir.mkdir()
    cases = [
        (("replay", str(not_a_bag), str(ros_robot), "--journal", str(tmp_path / "j1")),
         "not a rosbag2 bag"),
        (("replay", str(bag_dir), str(ros_robot), "--journal", str(tmp_path / "j2")),
         "not a rosbag2 bag"),
        (("replay", str(tmp_path / "missing"), str(ros_robot), "--journal",
          str(tmp_path / "j3")), "no such bag"),
        (("replay", str(bag_dir), str(zenoh_robot), "--journal", str(tmp_path / "j4")),
         "not ROS 2"),
        (("record", str(zenoh_robot), str(tmp_path / "b")), "not ROS 2"),
        (("record", str(ros_robot), str(bag_dir)), "exists already"),
        (("record", str(tmp_path), str(tmp_path / "b")), "no system.yaml"),
    ]
    for args, says in cases:
        p = dxboard(*args)
        assert p.returncode == 2, (args, p.stdout, p.stderr)
        lines = p.stderr.strip().splitlines()
        assert len(lines) == 1 and says in lines[0], (args, p.stderr)
        assert "Traceback" not in p.stderr
