"""``dxboard model learn`` on a robot that is not ours (issue 28, item 3), and from a bag.

The second robot (``second_robot/``: plain rclpy, no dxboard code) runs a camera-like publisher
at 20 Hz, a stage that republishes each frame at once (its output follows its input), and a
standard lifecycle node waiting, unconfigured, for a manager. The learner watches it for 8 s
through the real command; the written model must load as ``dxboard run`` loads it, with the
camera's rate within the publisher's truth, the message types right, the stage's subscription
as its output's dependency (and the lag noted), and the lifecycle node marked managed. The bag:
``rosbags`` writes a real rosbag2 file whose clock is hours away from now; the learner reads
the rate on the bag's clock.
"""

from __future__ import annotations

import subprocess
import sys
from collections.abc import Iterator
from pathlib import Path

import pytest
from rclpy.serialization import serialize_message
from sensor_msgs.msg import Image
from std_msgs.msg import String

from host.diagnosis.model import load_system
from host.learn.session import check_written
from host.observers.config import load_observers
from host.observers.payload import TopicMessage, encode
from host.observers.sources.ros2_graph import GRAPH
from host.observers.sources.ros2_message import RosMessage
from host.observers.topics import FrequencyObserver
from host.ros import graphlog
from host.ros.bag import BagWriter
from tests.ros.conftest import Peer
from tests.ros.test_bags import dxboard

HERE = Path(__file__).parent / "second_robot"
RATE = 20.0


@pytest.fixture
def second_robot(env: dict[str, str], peer: Peer) -> Iterator[None]:
    argvs = [[str(HERE / "camera.py"), "camera", "/camera/image", "--rate", str(RATE)],
             [str(HERE / "relay.py"), "rectify", "/camera/image", "/camera/rect"],
             [str(HERE / "lifecycle_node.py"), "lidar_driver"]]
    procs = [subprocess.Popen([sys.executable, *a], env=env, stdout=subprocess.DEVNULL,
                              stderr=subprocess.DEVNULL) for a in argvs]
    try:
        peer.listen("/camera/rect", Image)
        peer.collect("/camera/rect", 5, 120.0)  # the whole pipeline runs
        peer.wait_for(lambda: "lidar_driver" in peer.nodes(), "the lifecycle node", 120.0)
        yield
    finally:
        for p in procs:
            p.terminate()
        for p in procs:
            try:
                p.wait(20)
            except subprocess.TimeoutExpired:
                p.kill()
                p.wait(20)


def test_learn_the_second_robot(tmp_path: Path, env: dict[str, str], second_robot: None) -> None:
    out = tmp_path / "learned"
    p = dxboard("model", "learn", str(out), "--duration", "8", env=env)
    assert p.returncode == 0, p.stderr
    assert "watching the robot for 8 s" in p.stderr  # progress on stderr
    assert "joined the robot's ROS 2 graph" in p.stderr  # the watch began once all were found
    assert check_written(out) == []
    model = load_system(out)
    text = (out / "system.yaml").read_text()
    assert {"camera", "rectify", "lidar_driver"} <= set(model.components)
    assert model.components["rectify"].publishes == {"/camera/rect": ("/camera/image",)}
    assert model.components["rectify"].subscribes == ("/camera/image",)
    assert "lidar_driver: {lifecycle: true}" in text
    assert "camera: {lifecycle: true}" not in text
    assert "# sensor_msgs/msg/Image; n=" in text, (text, p.stderr)  # the watch, told
    topics = {o.topics[0]: o for o in load_observers(out, model).observers
              if isinstance(o, FrequencyObserver)}
    camera = topics["/camera/image"]
    assert abs(camera.rate - RATE) < 0.1 * RATE  # the publisher's truth, a timer on a busy box
    assert camera.tolerance < camera.rate
    assert "follows /camera/image" in text or "no steady lag behind /camera/image" in text


def test_learn_from_a_bag_on_its_clock(tmp_path: Path) -> None:
    bag = tmp_path / "bag"
    w = BagWriter(bag)
    t0 = 1_000_000.0  # the bag's clock: days before now
    for i in range(100):  # 10 Hz for 10 s
        msg = String(data=str(i))
        w.write(RosMessage(t0 + i * 0.1, "/chatter", bytes(serialize_message(msg)),
                           "std_msgs/msg/String"))
    w.write(graphlog.to_bag(TopicMessage(t0 + 5, GRAPH, encode({"nodes": ["talker"]}))))
    w.close(t0, t0 + 10)
    out = tmp_path / "learned"
    p = dxboard("model", "learn", str(out), "--bag", str(bag))
    assert p.returncode == 0, p.stderr
    text = (out / "system.yaml").read_text()
    assert "/chatter: {rate: 10, " in text and "n=100 over 9.9 s" in text
    assert "talker:" in text and "publisher_of_chatter" in text
    assert check_written(out) == []


def test_bad_input_is_one_line(tmp_path: Path) -> None:
    for args in (["--bag", str(tmp_path / "none")], ["--probe"], ["--duration", "0"],
                 ["--board", "nowhere"], ["--middleware", "zenoh", "--bag", "b"],
                 ["--middleware", "zenoh", "--zenoh-auth", str(tmp_path / "none")]):
        p = dxboard("model", "learn", str(tmp_path / "x"), *args)
        assert p.returncode == 2, (args, p.stderr)
        assert len(p.stderr.strip().splitlines()) == 1 and "Traceback" not in p.stderr
