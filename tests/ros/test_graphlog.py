"""Node presence in bags: the ROS 2 graph's samples as recorded messages and back.

A graph sample (the ROS 2 source's ``GRAPH`` pseudo-topic) goes into the bag's form (a real
``diagnostic_msgs/DiagnosticArray`` in CDR bytes, one key/value per node) and back to the
same node list at the same time; a graph observer fed from the bag's ``/dxboard/graph`` on
``ClockedObservers`` (as ``dxboard replay`` feeds it) says the node runs, then that it is gone.
"""

from __future__ import annotations

from diagnostic_msgs.msg import DiagnosticArray
from rclpy.serialization import deserialize_message

from host.observers import Retraction, Update
from host.observers.payload import TopicMessage, encode
from host.observers.sources.ros2_graph import GRAPH, GraphObserver
from host.ros import graphlog
from host.ros.offline import ClockedObservers, bag_observers


def sample(t: float, *nodes: str) -> TopicMessage:
    return TopicMessage(t, GRAPH, encode({"nodes": list(nodes)}))


def test_a_graph_sample_goes_into_the_bag_and_back() -> None:
    recorded = graphlog.to_bag(sample(1700000000.5, "imu_node", "hokuyo_node"))
    assert recorded.topic == graphlog.TOPIC and recorded.time == 1700000000.5
    array = deserialize_message(recorded.payload, DiagnosticArray)  # what a ROS tool reads
    assert array.header.stamp.sec == 1700000000 and array.status[0].message == "2 nodes"
    assert [kv.key for kv in array.status[0].values] == ["hokuyo_node", "imu_node"]
    back = graphlog.from_bag(recorded)
    assert back is not None and back.topic == GRAPH and back.time == recorded.time
    assert back.values == {"nodes": ["hokuyo_node", "imu_node"]}
    bad = type(recorded)(1.0, graphlog.TOPIC, b"\x00\x01\x00\x00junk", graphlog.TYPE)
    assert graphlog.from_bag(bad) is None


def test_a_graph_observer_on_the_bags_clock_sees_a_node_come_and_go() -> None:
    graph = GraphObserver("hokuyo_node")
    assert bag_observers([graph]) == [graph]
    out: list[tuple[str, float]] = []

    def sink(updates: list[Update], t: float) -> None:
        out.extend((u.atom if isinstance(u, Retraction) else str(u.literal), t)
                   for u in updates)

    clocked = ClockedObservers([graph], sink)
    assert clocked.topics == [graphlog.TOPIC]  # the bag's name for the graph
    clocked.start(10.0)
    for t, nodes in ((10.5, ("hokuyo_node",)), (11.5, ("hokuyo_node",)), (12.5, ())):
        clocked.feed(graphlog.to_bag(sample(t, *nodes)))
    assert ("running(hokuyo_node)", 10.5) in out
    assert ("~running(hokuyo_node)", 12.5) in out
