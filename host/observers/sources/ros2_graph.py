"""Node presence from the ROS 2 graph: ``running(n)`` iff a node named ``n`` is in the graph.

Paper 000's node observer watches processes; on a ROS 2 robot the graph itself says which
nodes are up, including those the daemon did not start (a driver on another computer of the
robot, a node launched by ``ros2 launch``). ``GraphObserver(node)`` is a topic observer of the
ROS 2 source's ``GRAPH`` pseudo-topic (``host.observers.sources.ros2``), whose messages carry
``{"nodes": [...]}`` every discovery period: it asserts ``running(node)`` when the name is
there and ``¬running(node)`` when it is not. DDS discovery takes a moment, so a node that has
just started may be reported absent for up to the discovery period (and one that was killed
without leaving the graph stays present until its lease expires, about 10 s with Fast DDS's
default lease; the process supervisor's node observer catches a death at once).
"""

from __future__ import annotations

import host.atoms as A
from host.observers.base import DEFAULT_REFRESH, DEFAULT_VALIDITY
from host.observers.payload import TopicMessage
from host.observers.topics import TopicObserver

GRAPH = "/_graph/nodes"  # = host.observers.sources.ros2.GRAPH (kept free of rclpy imports)


class GraphObserver(TopicObserver):
    kind = "graph"

    def __init__(self, node: str, *, name: str | None = None,
                 validity: float = DEFAULT_VALIDITY, refresh: float = DEFAULT_REFRESH) -> None:
        super().__init__(name or f"graph:{node}", validity, refresh)
        self.node = node
        self.topics = (GRAPH,)
        self.atom = str(A.running(node))

    def atoms(self) -> list[str]:
        return [self.atom]

    def _feed(self, item: TopicMessage, now: float) -> None:
        nodes = (item.values or {}).get("nodes")
        if isinstance(nodes, list):
            self._say(self.atom, self.node in nodes, now)
