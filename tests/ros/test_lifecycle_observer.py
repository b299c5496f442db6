"""A managed node's lifecycle state and a node's heartbeat as observations (issue 28, item 1).

Before this, a managed node was observed only by its presence in the graph: an unconfigured
node (in the graph, doing nothing) was ``running``, and a hung node that stays in the graph
was ``running`` until its topics' silence was judged. The pure observers are tested on a
simulated clock; the lifecycle state end to end with a plain rclpy lifecycle node
(``second_robot/lifecycle_node.py``) and the daemon's ROS 2 source, as the daemon reads it:
its ``get_state`` pseudo-topic and its transition events.
"""

from __future__ import annotations

import asyncio
import subprocess
import sys
from pathlib import Path
from typing import Any

import pytest

from host.diagnosis import load_system
from host.observers import ObserverConfigError, load_observers
from host.observers.base import Observer
from host.observers.payload import TopicMessage, encode
from host.observers.sources.ros2_lifecycle import (
    LIFECYCLE,
    HeartbeatObserver,
    LifecycleObserver,
    transition_event_topic,
)
from tests.observers.conftest import TEDUSAR
from tests.observers.test_config import model_text
from tests.ros.conftest import Peer

SUBJECT = Path(__file__).parent / "second_robot" / "lifecycle_node.py"
WAIT_S = 90.0


def said(updates: list[Any]) -> list[tuple[str, bool]]:
    return [(str(u.literal.atom), u.literal.positive) for u in updates if hasattr(u, "literal")]


def state_msg(node: str, state: str, t: float) -> TopicMessage:
    return TopicMessage(t, f"{LIFECYCLE}{node}", encode({"state": state}))


def test_lifecycle_state_is_running_only_while_active() -> None:
    o = LifecycleObserver("cam")
    assert o.topics == ("/_lifecycle/cam", "/cam/transition_event")
    # in the graph and answering, but unconfigured: not running (the graph said running)
    assert said(o.feed(state_msg("cam", "unconfigured", 0.0), 0.0)) == [("running(cam)", False)]
    assert said(o.feed(state_msg("cam", "configuring", 0.1), 0.1)) == []  # in transition
    assert o.state == "configuring"
    event = TopicMessage(0.2, "/cam/transition_event",
                    encode({"goal_state": {"id": 3, "label": "active"}}))
    assert said(o.feed(event, 0.2)) == [("running(cam)", True)]
    assert said(o.feed(state_msg("cam", "inactive", 0.3), 0.3)) == [("running(cam)", False)]
    assert said(o.feed(state_msg("cam", "active", 0.4), 0.4)) == [("running(cam)", True)]
    assert said(o.feed(state_msg("cam", "absent", 0.5), 0.5)) == [("running(cam)", False)]
    assert said(o.feed(state_msg("cam", "finalized", 0.6), 0.6)) == []  # still not running
    # nothing more from the source (a hung get_state): the literal expires to unknown
    assert [type(u).__name__ for u in o.tick(0.6 + o.validity)] == ["Retraction"]


def test_a_heartbeat_that_stops_is_not_running_after_its_timeout() -> None:
    o = HeartbeatObserver("planner", "/planner/heartbeat", timeout=0.5)
    assert o.tick(0.0) == [] and o.next_deadline() == 0.5  # the first beat is due by then
    beat = TopicMessage(0.1, "/planner/heartbeat")
    assert said(o.feed(beat, 0.1)) == [("running(planner)", True)]
    for t in (0.2, 0.3, 0.4):
        o.feed(TopicMessage(t, "/planner/heartbeat"), t)
    assert o.next_deadline() == pytest.approx(0.9)
    assert said(o.tick(0.85)) == []
    assert said(o.tick(0.9)) == [("running(planner)", False)]  # 0.5 s after the last beat
    assert said(o.feed(TopicMessage(2.0, "/planner/heartbeat"), 2.0)) == [
        ("running(planner)", True)]


def test_a_node_that_never_beats_is_not_running_after_its_timeout() -> None:
    o = HeartbeatObserver("planner", "/planner/heartbeat", timeout=0.5)
    o.tick(10.0)
    assert said(o.tick(10.5)) == [("running(planner)", False)]


def test_the_model_keys_build_the_observers_and_are_checked(tmp_path: Path) -> None:
    f = tmp_path / "system.yaml"
    f.write_text(model_text() + "observers:\n  nodes:\n    hokuyo_node: {lifecycle: true}\n"
                 "    imu_node: {heartbeat: /imu_node/heartbeat, timeout: 0.3}\n")
    cfg = load_observers(f, load_system(TEDUSAR))
    by_kind: dict[str, Observer[Any]] = {o.kind: o for o in cfg.observers}
    assert isinstance(by_kind["lifecycle"], LifecycleObserver)
    beat = by_kind["heartbeat"]
    assert isinstance(beat, HeartbeatObserver) and beat.timeout == 0.3
    assert beat.topics == ("/imu_node/heartbeat",)
    f.write_text(model_text() + "observers:\n  nodes:\n"
                 "    hokuyo_node: {lifecycle: true, graph: true}\n"
                 "    imu_node: {heartbeat: imu, timeout: 0.3}\n"
                 "    jaguar_node: {graph: true, timeout: 1}\n")
    with pytest.raises(ObserverConfigError) as err:
        load_observers(f, load_system(TEDUSAR))
    text = "\n".join(f"{p.message} ({p.fix})" for p in err.value.problems)
    assert "node 'hokuyo_node' gives ['graph', 'lifecycle']" in text
    assert "heartbeat 'imu' is not a topic (give heartbeat: /imu_node/heartbeat)" in text
    assert "timeout is the heartbeat's" in text


async def _until(o: LifecycleObserver, value: bool | None, state: str) -> None:
    """Until the observer says ``value`` of running(node) with the node in ``state``."""
    loop = asyncio.get_running_loop()
    end = loop.time() + WAIT_S
    while o.asserted.get(o.atom) is not value or o.state != state:
        assert loop.time() < end, f"waiting for {state}: still {o.asserted} in {o.state}"
        await asyncio.sleep(0.1)


async def test_the_ros2_source_observes_a_lifecycle_node_through_get_state_and_events(
        env: dict[str, str], domain: int) -> None:
    from host.observers.sources.ros2 import Ros2Source
    from host.observers.sources.ros2_node import RosNode
    from host.ros.manager import LifecycleManager

    node = "lc_observed"
    proc = subprocess.Popen([sys.executable, str(SUBJECT), node], env=env,
                            stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    source = Ros2Source(domain, discovery_s=0.2)
    ros = RosNode("dxboard_lifecycle_manager", domain)
    o = LifecycleObserver(node)
    topics: list[str] = []
    try:
        def on(msg: TopicMessage) -> None:
            topics.append(msg.topic)
            o.feed(msg, msg.time)
        for topic in o.topics:
            source.subscribe(topic, on)
        await _until(o, False, "unconfigured")  # waiting for a manager: in the graph, idle
        manager = LifecycleManager(ros, call_timeout_s=5.0, settle_s=WAIT_S)
        await manager.activate(node)
        await _until(o, True, "active")
        await manager.transition(node, "deactivate")
        await _until(o, False, "inactive")
        assert transition_event_topic(node) in topics  # the events were seen too
        proc.terminate()
        proc.wait(30)
        await _until(o, False, "absent")  # gone from the graph
    finally:
        proc.kill()
        proc.wait(30)
        ros.close()
        source.close()


async def test_a_hung_node_that_stays_in_the_graph_is_found_by_its_heartbeat(
        peer: Peer, domain: int) -> None:
    """A plain rclpy node beats on ``/NODE/heartbeat`` (``std_msgs/Empty``, 20 Hz); the
    daemon's ROS 2 source learns the type from the graph; the node stops beating (hung) but
    stays in the graph, where the graph observer still sees it: the heartbeat says it is not
    running."""
    from std_msgs.msg import Empty

    from host.observers.sources.ros2 import Ros2Source
    from host.observers.sources.ros2_graph import GRAPH, GraphObserver

    node = peer.node.get_name()
    beat, graph = HeartbeatObserver(node, f"/{node}/heartbeat", 0.5), GraphObserver(node)
    publisher = peer.node.create_publisher(Empty, f"/{node}/heartbeat", 10)
    timer = peer.node.create_timer(0.05, lambda: publisher.publish(Empty()))
    source = Ros2Source(domain, discovery_s=0.2)
    loop = asyncio.get_running_loop()
    try:
        source.subscribe(f"/{node}/heartbeat", lambda m: beat.feed(m, m.time))
        source.subscribe(GRAPH, lambda m: graph.feed(m, m.time))

        async def until(probe: Any, what: str) -> None:
            end = loop.time() + WAIT_S
            while not probe():
                assert loop.time() < end, f"{what}: heartbeat {beat.asserted}, graph " \
                                          f"{graph.asserted}"
                beat.tick(source.clock())
                await asyncio.sleep(0.05)

        await until(lambda: beat.asserted.get(beat.atom) is True
                    and graph.asserted.get(graph.atom) is True, "beating, in the graph")
        timer.cancel()  # hung: no more beats, still in the graph
        await until(lambda: beat.asserted.get(beat.atom) is False, "the beats stopped")
        assert graph.asserted.get(graph.atom) is True  # the graph alone still says running
    finally:
        source.close()
