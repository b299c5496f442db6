"""Bags of the robot ``make run`` starts: ``record`` and ``replay`` take ``--middleware`` as ``run``
does, and the recorder says "recording" only once it is subscribed and matched.

The robot directory is the real TEDUSAR model (its ``system.yaml`` says zenoh, as the one
``make run`` starts with ``--middleware ros2``); nothing in it is edited to say ROS 2. The
fault's start: with the virtual robot's Hokuyo driver publishing ``/scan`` over ROS 2, the test
starts ``dxboard record --middleware ros2``, waits for its "recording" line and injects the
Hokuyo's hang at once: the bag must hold ``/scan`` messages from before the hang (the fault's
start), then its silence, and the replay must see ``/scan`` go from ok to silent.
"""

from __future__ import annotations

import signal
import subprocess
import time
from pathlib import Path

from sensor_msgs.msg import LaserScan

from host.ros.bag import Bag
from tests.robot.conftest import DXBOARD, ROOT, Robot
from tests.ros.conftest import Peer, RosNodes
from tests.ros.test_bags import dxboard, seen
from tests.wait import wait_until

WAIT_S = 120.0


def test_record_and_replay_take_the_middleware_of_run(tmp_path: Path, robot_dir: Path,
                                                       env: dict[str, str]) -> None:
    assert "\n  source: {kind: ros2}" not in (robot_dir / "system.yaml").read_text()
    bag = tmp_path / "short"
    p = dxboard("record", str(robot_dir), str(bag), "--middleware", "ros2", "--duration", "1",
                "--wait", "1", env=env)
    assert p.returncode == 0, p.stderr
    assert p.stdout.startswith("recording") and "wrote" in p.stdout
    p = dxboard("replay", str(bag), str(robot_dir), "--middleware", "ros2", "--journal",
                str(tmp_path / "r.sqlite"), env=env)
    assert p.returncode == 0, p.stderr
    # $DXBOARD_MIDDLEWARE, as `run` reads it
    p = dxboard("replay", str(bag), str(robot_dir), "--journal", str(tmp_path / "e.sqlite"),
                env={**env, "DXBOARD_MIDDLEWARE": "ros2"})
    assert p.returncode == 0, p.stderr
    # zenoh is not a bag's middleware: one line, exit 2, no traceback
    p = dxboard("record", str(robot_dir), str(tmp_path / "z"), "--middleware", "zenoh",
                "--duration", "1", env=env)
    assert p.returncode == 2
    assert "Traceback" not in p.stderr and len(p.stderr.strip().splitlines()) == 1, p.stderr
    assert "--middleware ros2" in p.stderr


def test_the_recorder_has_the_start_of_a_fault_injected_as_it_says_recording(
        tmp_path: Path, robot_dir: Path, robot: Robot, ros_nodes: RosNodes, peer: Peer,
        env: dict[str, str]) -> None:
    bag, live = tmp_path / "hang", tmp_path / "live.sqlite"
    robot.board("on", "hokuyo")
    peer.listen("/scan", LaserScan)
    ros_nodes.start("hokuyo_node")
    peer.collect("/scan", 5, WAIT_S)  # the robot is up and publishing
    rec = subprocess.Popen([DXBOARD, "record", str(robot_dir), str(bag), "--middleware", "ros2",
                            "--journal", str(live)],
                           stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=env,
                           cwd=ROOT)
    try:
        assert rec.stdout is not None
        line = rec.stdout.readline()
        # subscribed and matched: /scan is not among the topics nobody publishes yet (only
        # the Hokuyo's driver runs here)
        assert line.startswith(f"recording tedusar into {bag} (no publisher yet: "), line
        assert "/board_stream" in line and "/scan" not in line, line
        hang = time.time()
        robot.inject("hokuyo", "hang")  # at once
        wait_until(lambda: seen(live, "ok(/scan)", False), WAIT_S,
                   "the recorder saw /scan fall silent", show=rec.poll)
    finally:
        rec.send_signal(signal.SIGINT)
        _, err = rec.communicate(timeout=WAIT_S)
    assert rec.returncode == 0, err
    b = Bag(bag)
    try:
        scans = [m.time for m in b.messages() if m.topic == "/scan"]
    finally:
        b.close()
    assert [t for t in scans if t < hang], f"no /scan before the hang at {hang}: {scans[:3]}"
    assert len([t for t in scans if t >= hang]) < len(scans)  # and its silence after

    replayed = tmp_path / "replay.sqlite"
    p = dxboard("replay", str(bag), str(robot_dir), "--middleware", "ros2", "--journal",
                str(replayed), env=env)
    assert p.returncode == 0, p.stderr
    assert seen(replayed, "ok(/scan)", False)
