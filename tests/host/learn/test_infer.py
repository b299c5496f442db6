"""The learner's core on synthetic samples (in-process): rates as ROS 2 topic statistics define
them, periodic against reactive, dependencies from subscriptions, time and probes, devices from
probes, current bands, and a written model that loads as ``dxboard run`` loads it."""

from __future__ import annotations

import math
import random
from pathlib import Path

import pytest

from host.learn.infer import infer, lag
from host.learn.recording import ChannelProbe, ChannelSeen, NodeSeen, Recording
from host.learn.render import render
from host.learn.session import check_written
from host.learn.stats import learn_rate, period_windows, propose


def ticks(rate: float, span: float, jitter: float = 0.0, start: float = 0.0,
          seed: int = 1) -> list[float]:
    rng = random.Random(seed)
    return [start + i / rate + rng.gauss(0, jitter) for i in range(int(span * rate))]


def test_period_windows_are_ros2_topic_statistics() -> None:
    ws = period_windows([0.0, 0.1, 0.2, 0.4, 1.0, 1.1], 1.0)
    # window [0, 1): periods 0.1, 0.1, 0.2; window [1, 2): 0.6, 0.1
    assert [w.count for w in ws] == [3, 2]
    assert ws[0].mean == pytest.approx(0.4 / 3) and ws[0].max == pytest.approx(0.2)
    assert ws[1].max == pytest.approx(0.6) and ws[1].stddev == pytest.approx(0.25)


@pytest.mark.parametrize("rate", [0.5, 9.0, 40.0, 100.0])
def test_a_periodic_topic_gets_an_observer_that_its_own_jitter_keeps_ok(rate: float) -> None:
    times = ticks(rate, 60, jitter=0.05 / rate)
    ev = learn_rate(times)
    assert ev is not None and ev.periodic and ev.n == len(times)
    assert ev.rate == pytest.approx(rate, rel=0.02)
    p = propose(ev)
    assert p is not None and p.rate == pytest.approx(rate, rel=0.02)
    assert p.tolerance < p.rate  # a silent topic is never ok
    assert p.window * p.rate >= 2 and p.silence >= 4
    # every window of its own recording is within the tolerance
    for w in period_windows(times, p.window)[:-1]:
        assert abs(w.count / p.window - p.rate) < p.tolerance


def events(rate: float, span: float, seed: int) -> list[float]:
    """Random events (a Poisson process) at ``rate`` for ``span`` s."""
    rng = random.Random(seed)
    t, times = 0.0, []
    while t < span:
        times.append(t)
        t += rng.expovariate(rate)
    return times


def test_a_reactive_topic_gets_no_rate_observer() -> None:
    ev = learn_rate(events(2.0, 60, 3))
    assert ev is not None and not ev.periodic and propose(ev) is None


def test_too_few_samples_back_nothing() -> None:
    assert learn_rate([0.0, 1.0, 2.0]) is None


def test_lag_tells_a_follower_from_a_timer() -> None:
    scans = ticks(40, 20)
    follower = [t + 0.003 for t in scans]
    timer = ticks(7.3, 20, start=0.011)
    assert lag(follower, scans, 40).follows  # type: ignore[union-attr]
    assert not lag(timer, scans, 40).follows  # type: ignore[union-attr]


def robot(probe: bool = True) -> Recording:
    rec = Recording(0.0, 33.0, source="synthetic samples")
    for t in ticks(40, 30, 0.0005):
        rec.add("/scan", t, "sensor_msgs/msg/LaserScan")
        rec.add("/cloud", t + 0.004, "sensor_msgs/msg/PointCloud2")
    for t in ticks(20, 30, 0.001):
        rec.add("/odom", t, "nav_msgs/msg/Odometry")
    for t in ticks(0.5, 30, start=0.3):
        rec.add("/map", t, "nav_msgs/msg/OccupancyGrid")
    rec.add("/rosout", 1.0, "rcl_interfaces/msg/Log")
    for t in ticks(2, 30):  # two drivers' statuses (REP-107): status plumbing, not data
        rec.add("/diagnostics", t, "diagnostic_msgs/msg/DiagnosticArray")
    rec.nodes = {
        "lidar": NodeSeen("lidar", ("/scan", "/rosout", "/diagnostics"), (), managed=True),
        "base": NodeSeen("base", ("/odom", "/diagnostics"), ()),
        "filter": NodeSeen("filter", ("/cloud",), ("/scan",)),
        "mapper": NodeSeen("mapper", ("/map",), ("/scan", "/odom")),
    }
    rec.channels = {0: ChannelSeen(0, "lidar_power", currents=(0.5, 0.55, 0.6)),
                    1: ChannelSeen(1, "pc", protected=True, currents=(2.0,)),
                    2: ChannelSeen(2, "spare"),
                    3: ChannelSeen(3, "wheels", currents=(1.0, 3.0))}
    if probe:
        rec.probes = [ChannelProbe(0, 30.0, 31.6, ("/scan", "/cloud", "/map"), ("/odom",), ()),
                      ChannelProbe(3, 31.6, 33.0, ("/odom",), ("/scan", "/cloud", "/map"),
                                   ("base",))]
    return rec


def test_structure_from_the_graph_and_the_probes() -> None:
    m = infer(robot(), "bot")
    nodes = {n.name: n for n in m.nodes}
    assert sorted(t.name for t in m.topics) == ["/cloud", "/map", "/odom", "/scan"]
    assert nodes["lidar"].managed and not nodes["base"].managed
    assert nodes["filter"].publishes == {"/cloud": ("/scan",)}
    # /map stopped with /scan but went on while /odom stopped: it depends on /scan only
    assert nodes["mapper"].publishes == {"/map": ("/scan",)}
    devices = {d.channel: d for d in m.devices}
    assert sorted(devices) == [0, 3]  # the protected channel is never a device
    assert nodes["lidar"].hardware == ("lidar_power",) and nodes["lidar"].kind == "SN"
    assert nodes["base"].hardware == ("wheels",)
    assert nodes["filter"].kind == "N" and nodes["mapper"].kind == "N"  # fed by the driver
    lo, hi = devices[0].band or (0, 0)
    assert lo < 0.5 and hi > 0.6 and devices[0].n == 3
    assert m.protected == (1,) and m.idle == (2,)
    assert any("follows /scan" in note for note in nodes["filter"].notes["/cloud"])


def test_without_a_probe_the_graph_alone(tmp_path: Path) -> None:
    m = infer(robot(probe=False), "bot")
    nodes = {n.name: n for n in m.nodes}
    assert nodes["mapper"].publishes == {"/map": ("/scan", "/odom")}
    assert all(n.kind == "N" for n in m.nodes)


def test_the_written_model_loads_and_carries_its_evidence(tmp_path: Path) -> None:
    text = render(infer(robot(), "bot"))
    (tmp_path / "system.yaml").write_text(text)
    assert check_written(tmp_path) == []
    assert "/scan: {rate: 40, " in text
    assert "n=1200 over " in text  # the evidence of /scan's rate
    assert "lidar: {lifecycle: true}" in text and "kind: SH" in text
    assert "probe: channel 0 off" in text
    assert "/rosout" not in text and "/diagnostics" not in text


def test_a_topic_without_a_known_publisher_is_named_for_review(tmp_path: Path) -> None:
    rec = Recording(0.0, 10.0, source="a bag")
    for t in ticks(10, 10):
        rec.add("/chatter", t, "std_msgs/msg/String")
    text = render(infer(rec, "bot", ros2=False))
    assert "publisher_of_chatter" in text and "rename" in text
    (tmp_path / "system.yaml").write_text(text)
    assert check_written(tmp_path) == []


def test_a_busy_receiver_bunching_a_periodic_topic_does_not_make_it_reactive() -> None:
    sent = ticks(40, 60, jitter=0.0005)
    bunched = [math.ceil(t / 0.4) * 0.4 + 0.001 * (i % 7) for i, t in enumerate(sent)]
    lost = [t for i, t in enumerate(sent) if i % 9 != 4]  # and one message in 9 lost
    by_stamps = learn_rate(bunched[:len(lost)], lost)
    assert by_stamps is not None and by_stamps.clock == "sender" and by_stamps.periodic
    assert by_stamps.rate == pytest.approx(40, rel=0.02)  # the sender's rate, losses aside
    by_arrivals = learn_rate(bunched)
    assert by_arrivals is not None and by_arrivals.clock == "arrival" and by_arrivals.periodic
    assert by_arrivals.rate == pytest.approx(40, rel=0.02)


def test_random_events_on_the_senders_clock_are_reactive() -> None:
    times = events(5.0, 60, 5)
    ev = learn_rate([x + 0.01 for x in times], times)
    assert ev is not None and ev.clock == "sender" and not ev.periodic


def test_a_load_a_probe_shows_nothing_needs_is_no_component(tmp_path: Path) -> None:
    """A channel that draws current but whose probe stopped no topic and no node (a router, a
    sensor head's fan: TEDUSAR's channels 0, 4, 5) is no component of the diagnosis model, as
    the hand-written model has none: a board-wide fault would otherwise power it up as a
    repair. It is written as a commented-out component with its evidence, for the review."""
    rec = robot()
    rec.channels[4] = ChannelSeen(4, "router", currents=(0.3, 0.32, 0.31))
    rec.probes.append(ChannelProbe(4, 33.0, 34.5, (), ("/scan", "/cloud", "/map", "/odom"), ()))
    m = infer(rec, "bot")
    assert sorted(d.channel for d in m.devices) == [0, 3]
    assert [d.channel for d in m.loads] == [4]
    assert m.idle == (2,)
    text = render(m)
    (tmp_path / "system.yaml").write_text(text)
    assert check_written(tmp_path) == []
    assert "\n  router:" not in text
    assert "#   router: {kind: SH, channel: 4, current: [" in text
    assert "probe stopped no topic and no node" in text
    # without a probe such a channel stays a device with no known driver: nothing tells
    m = infer(robot(probe=False), "bot")
    assert sorted(d.channel for d in m.devices) == [0, 3] and m.loads == ()


def test_a_topic_too_slow_for_the_probes_window_is_not_judged_stopped() -> None:
    """A 0.5 Hz map sends nothing in a 1.5 s probe whatever the channel: its silence is no
    evidence (TEDUSAR's mapper was made the driver of the laser's leveling mount, whose probe
    happened to fall between two maps). A message during the probe still shows it went on."""
    rec = robot()
    rec.channels[5] = ChannelSeen(5, "mount", currents=(0.2, 0.25))
    rec.probes.append(ChannelProbe(5, 33.0, 34.5, ("/map",), ("/scan", "/cloud", "/odom"), ()))
    m = infer(rec, "bot")
    nodes = {n.name: n for n in m.nodes}
    assert nodes["mapper"].hardware == () and nodes["mapper"].kind == "N"
    assert [d.channel for d in m.loads] == [5]  # nothing judged stopped: a load
    assert nodes["mapper"].publishes == {"/map": ("/scan",)}  # probe 3's evidence stands
