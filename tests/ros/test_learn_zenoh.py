"""``dxboard model learn --middleware zenoh`` on the robot ``make run`` starts (issue 28, item 2).

The virtual TEDUSAR robot under ``dxboard run --emulate`` (its nodes publish over Zenoh to the
daemon's endpoint, which admits only peers with the daemon's credentials file), once healthy,
is watched for 8 s by the real command with that endpoint and file and the emulated board's
address: the written model must load as ``dxboard run`` loads it, hold the robot's topics with
their rates near the nodes' truth and their evidence (``n=``), and the board's powered
channels as devices with current bands and their readings' evidence. Zenoh has no node graph:
each topic's publisher is named for the review. Before, the command refused zenoh (exit 2).
"""

from __future__ import annotations

from collections.abc import Iterator
from pathlib import Path

import pytest

from host.diagnosis.model import load_system
from host.learn.session import check_written
from host.observers.config import load_observers
from host.observers.topics import FrequencyObserver
from tests.daemon.runner import RunningDaemon, fast_copy, healthy, key_file
from tests.ros.test_bags import dxboard

HEAL_S = 180.0  # a power-up of the whole robot on a loaded 2-core machine


@pytest.fixture
def robot(tmp_path: Path) -> Iterator[RunningDaemon]:
    d = RunningDaemon(tmp_path, fast_copy(tmp_path),
                      extra_args=("--key-file", str(key_file(tmp_path))))
    try:
        d.wait_for(healthy, HEAL_S, "the robot powered up and healthy")
        yield d
    finally:
        d.close()


def test_learn_the_robot_make_run_starts_over_zenoh(tmp_path: Path,
                                                     robot: RunningDaemon) -> None:
    out = tmp_path / "learned"
    board = robot.urls["board"].removeprefix("tcp://")
    p = dxboard("model", "learn", str(out), "--middleware", "zenoh", "--zenoh", robot.zenoh,
                "--zenoh-auth", str(robot.auth), "--board", board, "--duration", "8")
    assert p.returncode == 0, p.stderr
    assert check_written(out) == []
    text = (out / "system.yaml").read_text()
    assert "from the running robot (Zenoh)" in text
    assert "source: {kind: ros2}" not in text  # the model observes through zenoh, the default
    model = load_system(out)
    rates = {o.topics[0]: o.rate for o in load_observers(out, model).observers
             if isinstance(o, FrequencyObserver)}
    for topic, truth in (("/scan", 40.0), ("/odom", 20.0)):  # the written model's rates
        lines = [ln for ln in text.splitlines() if topic[1:] in ln]
        assert abs(rates.get(topic, 0.0) - truth) < 0.2 * truth, (topic, rates, lines)
    assert "publisher_of_scan:" in text and "rename" in text  # no node graph over zenoh
    assert "# type unknown; n=" in text  # each rate with its evidence (zenoh has no types)
    devices = {c.channel: c for c in model.components.values() if c.channel is not None}
    # the powered devices (hokuyo 3, jaguar 7) draw current in bands learned from readings
    for ch in (3, 7):
        assert devices[ch].current is not None, text
    assert "readings from" in text
    assert 2 not in devices  # the protected pc channel is never a device
