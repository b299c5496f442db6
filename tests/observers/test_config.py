"""The ``observers:`` section: the tedusar observers of paper 000 §VI, and the loader's errors."""

from __future__ import annotations

import os
from pathlib import Path

import pytest

from host.diagnosis import generate, load_system
from host.observers import (
    FrequencyObserver,
    HardwareObserver,
    NodeObserver,
    ObserverConfigError,
    check_atoms,
    load_observers,
)
from tests.observers.conftest import TEDUSAR

TEDUSAR_OBSERVERS = """
observers:
  refresh: 1.0
  validity: 3.0
  source: {kind: zenoh, listen: [tcp/127.0.0.1:7447]}
  hardware: {link_timeout: 0.25, settle: 3}
  nodes:
    jaguar_node: {supervised: true}
    hokuyo_node: {supervised: true}
    laser_alignment_node: {supervised: true}
    imu_node: {supervised: true}
    joy_node: {supervised: true}
    jaguar_teleop_node: {supervised: true}
    hector_mapping: {match: 'hector_mapping'}
    laser_alignment_control: {supervised: true}
  topics:
    /odom: {rate: 10, tolerance: 3, window: 1.0}
    /map: {rate: 0.5, tolerance: 0.3, window: 6.0, silence: 3}
    /scan: {rate: 40, tolerance: 10, window: 0.5}
    /imu_data: {rate: 100, tolerance: 25, window: 0.5}
    /cmd_vel: {rate: 10, tolerance: 4, window: 1.0}
"""


def model_text() -> str:
    """The tedusar model without its own ``observers:`` section (the last one in the file)."""
    text = (TEDUSAR / "system.yaml").read_text()
    return text[: text.index("\nobservers:\n") + 1]


def write(tmp_path: Path, text: str) -> Path:
    f = tmp_path / "system.yaml"
    f.write_text(model_text() + text)
    return f


def test_tedusar_observers_of_the_paper(tmp_path: Path) -> None:
    model = load_system(TEDUSAR)
    cfg = load_observers(write(tmp_path, TEDUSAR_OBSERVERS), model)
    kinds = [o.kind for o in cfg.observers]
    assert kinds.count("hardware") == 1 and kinds.count("node") == 8  # rviz: not on the robot
    assert kinds.count("frequency") == 5
    hw = next(o for o in cfg.observers if isinstance(o, HardwareObserver))
    # the paper's three and the missions' thermal camera (beyond the paper's model)
    assert set(hw.devices) == {"jaguar", "hokuyo", "laser_alignment", "thermal_camera"}
    assert hw.devices["hokuyo"].channel == 3 and hw.devices["hokuyo"].band == (0.2, 1.2)
    scan = next(o for o in cfg.observers if isinstance(o, FrequencyObserver)
                and o.topics == ("/scan",))
    assert scan.rate == 40 and scan.max_gap == pytest.approx(4 / 40)  # 4 periods: default
    assert cfg.processes["hector_mapping"].match == "hector_mapping"
    assert cfg.processes["jaguar_node"].supervised
    assert all(isinstance(o, NodeObserver) for o in cfg.observers if o.kind == "node")
    # every atom is one the generated model knows, the board link's included
    assert check_atoms(cfg, generate(model)) == []
    # and the committed model's own section says the same as the paper's list above, and
    # observes the missions' thermal camera beyond it (its driver and its image topic)
    own = load_observers(TEDUSAR / "system.yaml", model)
    assert sorted(o.kind for o in own.observers) == sorted([*kinds, "node", "frequency"])
    assert check_atoms(own, generate(model)) == []


def test_config_errors_name_file_line_and_fix(tmp_path: Path) -> None:
    text = """
observers:
  validity: 0.5
  topics:
    /odom: {rate: 10, tolerance: 3, window: 0.1}
    /nowhere: {rate: 10}
    odom: {rate: 10}
  nodes:
    imu: {match: imu}
    rviz: {}
  trends:
    v: {topic: /odom, key: yaw, slope: -1}
  matched: [[v, w]]
  diagnostics:
    /odom: [{key: t, literal: "ok(temp"}]
  responses:
    - {input: /cmd_vel, output: /cmd_vel, within: 0.2}
  bogus: 1
"""
    f = write(tmp_path, text)
    base = len(model_text().splitlines())
    with pytest.raises(ObserverConfigError) as err:
        load_observers(f, load_system(TEDUSAR))
    got = {(p.line - base, p.message.split(" ")[0]) for p in err.value.problems}
    problems = err.value.problems
    assert all(p.file == f and p.fix for p in problems)
    text_of = [f"{p.line - base}: {p.message} ({p.fix})" for p in problems]
    expect = [
        (3, "validity 0.5 s is not above refresh"),
        (5, "window 0.1 s holds fewer than 2 messages"),
        (6, "topic /nowhere is published by no component"),
        (7, "'odom' is not a topic name"),
        (9, "'imu' is not a node of the model"),
        (10, "node 'rviz' gives none of pid, match, supervised"),
        (12, "slope -1 is not a number >= 0"),
        (13, "matched names ['w'], not declared under trends"),
        (15, "'ok(temp' is not an atom"),
        (17, "input and output are the same topic"),
        (18, "unknown key 'bogus'"),
    ]
    for line, words in expect:
        assert any(t.startswith(f"{line}: ") and words in t for t in text_of), (line, words,
                                                                                text_of)
    assert got  # every problem has a line
    assert str(err.value).startswith(f"{f}:")


def test_without_a_model_the_devices_are_listed(tmp_path: Path) -> None:
    f = tmp_path / "system.yaml"
    f.write_text("observers:\n  hardware:\n    devices: {fan: {channel: 4}}\n"
                 "  topics: {/x: {rate: 5}}\n")
    cfg = load_observers(f)
    hw = cfg.observers[0]
    assert isinstance(hw, HardwareObserver) and hw.devices["fan"].band is None
    f.write_text("observers:\n  hardware: {}\n")
    with pytest.raises(ObserverConfigError, match=r"system.yaml:2: no devices"):
        load_observers(f)


def test_two_observers_for_one_atom_is_an_error(tmp_path: Path) -> None:
    f = tmp_path / "system.yaml"
    f.write_text("observers:\n  topics: {/odom: {rate: 10}}\n"
                 "  responses: [{input: /cmd_vel, output: /odom, within: 0.5}]\n")
    with pytest.raises(ObserverConfigError, match="ok\\(/odom\\) is emitted by two observers"):
        load_observers(f)


def test_the_link_slack_is_read_and_checked(tmp_path: Path) -> None:
    f = tmp_path / "system.yaml"
    f.write_text("observers:\n  hardware:\n    devices: {fan: {channel: 4}}\n"
                 "    link_timeout: 0.3\n    link_slack: 0\n")
    hw = load_observers(f).observers[0]
    assert isinstance(hw, HardwareObserver)
    assert (hw.link_timeout, hw.link_slack, hw.link_limit) == (0.3, 0.0, 0.3)
    f.write_text("observers:\n  hardware:\n    devices: {fan: {channel: 4}}\n"
                 "    link_slack: -1\n")
    with pytest.raises(ObserverConfigError, match=r"system.yaml:4: link_slack -1 is not"):
        load_observers(f)
    # the default: the link limit may grow by 0.75 s on a busy machine
    hw = load_observers(TEDUSAR / "system.yaml", load_system(TEDUSAR)).observers[0]
    assert isinstance(hw, HardwareObserver) and hw.link_slack == 0.75


def test_own_time_is_read_checked_and_keeps_a_topic_from_its_probe(tmp_path: Path) -> None:
    from host.observers.starvation import wire_probes
    f = write(tmp_path, "observers:\n  topics:\n    /scan: {rate: 40, own_time: false}\n"
              "    /odom: {rate: 20}\n")
    model = load_system(f)
    scan, odom = load_observers(f, model).observers
    assert isinstance(scan, FrequencyObserver) and isinstance(odom, FrequencyObserver)
    assert (scan.own_time, odom.own_time) == (False, True)
    wired = wire_probes([scan, odom], model, lambda node: None, {}, way_in=[os.getpid()])
    assert list(wired) == ["/odom"] and scan.probe is None and odom.probe is not None
    # the daemon alone says nothing of /odom's publisher (jaguar_node, not found yet)
    assert odom.probe.read() is None
    f = write(tmp_path, "observers:\n  topics:\n    /scan: {rate: 40, own_time: maybe}\n")
    with pytest.raises(ObserverConfigError, match=r"own_time 'maybe' is not true or false"):
        load_observers(f, model)
