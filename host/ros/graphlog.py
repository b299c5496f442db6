"""Node presence in bags: the ROS 2 graph's node list as a recorded message, and back.

The ROS 2 graph is not a topic: the ROS 2 source samples it every discovery period (the
``GRAPH`` pseudo-topic, ``host.observers.sources.ros2``) for the graph observers
(``sources.ros2_graph``, ``running(n)``). ``dxboard record`` writes each sample into the bag on
``/dxboard/graph`` (a topic only bags have: nothing publishes it over DDS) as a standard
``diagnostic_msgs/DiagnosticArray``, so ``ros2 bag``, Foxglove and ``rosbags`` read it:

- ``header.stamp``: when the graph was sampled (the recorder's wall clock);
- one status named ``dxboard graph``, ``hardware_id`` ``ros2 graph``, level OK, message the
  number of nodes (``"7 nodes"``), and one key/value per node in the graph: key the node's
  name, value ``present``.

``to_bag(msg)`` turns a ``GRAPH`` sample into that message, ``from_bag(msg)`` a recorded one
back into the sample the graph observers read (None: not one; logged).
"""

from __future__ import annotations

import logging

from host.observers.payload import TopicMessage, encode
from host.observers.sources.ros2_graph import GRAPH
from host.observers.sources.ros2_message import RosMessage
from host.ros.boardstream import set_stamp

log = logging.getLogger(__name__)

TOPIC = "/dxboard/graph"
TYPE = "diagnostic_msgs/msg/DiagnosticArray"
NAME = "dxboard graph"


def to_bag(sample: TopicMessage) -> RosMessage:
    """A ``GRAPH`` sample as the message the bag holds (at the sample's time)."""
    from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus, KeyValue
    from rclpy.serialization import serialize_message

    nodes = (sample.values or {}).get("nodes")
    names = sorted(str(n) for n in nodes) if isinstance(nodes, list) else []
    msg = DiagnosticArray()
    set_stamp(msg.header, sample.time)
    msg.status = [DiagnosticStatus(
        level=b"\x00", name=NAME, message=f"{len(names)} nodes", hardware_id="ros2 graph",
        values=[KeyValue(key=n, value="present") for n in names])]
    return RosMessage(sample.time, TOPIC, bytes(serialize_message(msg)), TYPE)


def from_bag(msg: RosMessage) -> TopicMessage | None:
    """The graph sample a recorded ``/dxboard/graph`` message carries, at its bag time."""
    from diagnostic_msgs.msg import DiagnosticArray
    from rclpy.serialization import deserialize_message

    try:
        array = deserialize_message(msg.payload, DiagnosticArray)
        status = next(s for s in array.status if s.name == NAME)
    except Exception as exc:  # bad CDR, no such status
        log.warning("%s at %.3f: not a graph sample (%s)", msg.topic, msg.time, exc)
        return None
    return TopicMessage(msg.time, GRAPH, encode({"nodes": [kv.key for kv in status.values]}))
