"""A ``Recording`` from a rosbag2 bag: the same learning on the bag's clock (``--bag BAG``).

Every message's bag time is its arrival (``host.ros.bag``: the time the recorder received it);
the bag's own start and end marks bound the recording. A bag holds topics, not the graph's
publishers and subscribers: the nodes present come from the graph samples ``dxboard record``
writes on ``/dxboard/graph`` (``host.ros.graphlog``), without their topics, so ``infer`` names
each topic's publisher after the topic for the reviewer to rename; a bag has no board
readings and no probes.
"""

from __future__ import annotations

from pathlib import Path

from host.learn.recording import NodeSeen, Recording
from host.ros import graphlog
from host.ros.bag import Bag


def read_bag(path: Path) -> Recording:
    """The recording a bag holds. Raises ``UserError`` for anything not a readable bag."""
    bag = Bag(path)
    try:
        rec = Recording(bag.start, bag.end, source=f"the bag {path}")
        for msg in bag.messages():
            if msg.topic == graphlog.TOPIC:
                sample = graphlog.from_bag(msg)
                nodes = (sample.values or {}).get("nodes") if sample is not None else None
                for name in nodes if isinstance(nodes, list) else []:
                    rec.nodes.setdefault(str(name), NodeSeen(str(name)))
                continue
            stamp = msg.stamp
            rec.add(msg.topic, msg.time, msg.type_name, stamp=stamp or None)
        rec.end = max([rec.end, *(ts[-1] for ts in rec.arrivals.values() if ts)])
        return rec
    finally:
        bag.close()
