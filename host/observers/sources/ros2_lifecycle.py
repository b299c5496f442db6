"""A managed node's lifecycle state and a node's heartbeat, as observations of ``running(n)``.

Two node observers for ROS 2 robots, beside the graph's presence (``ros2_graph``), chosen
per node in ``observers: nodes:`` of ``system.yaml``:

``{lifecycle: true}``: ``LifecycleObserver(node)``. A managed node (``rclpy.lifecycle``,
``rclcpp_lifecycle``) does its work only while *active*: unconfigured or inactive it is in the
graph, answers its services and publishes nothing. So ``running(n)`` is its lifecycle state
being ``active``, ``¬running(n)`` when it is ``unconfigured``, ``inactive`` or ``finalized``,
or when the node is gone from the graph; the repair domain's ``activate_node`` and
``reset_node`` read ``running`` the same way. The state comes from two inputs of the ROS 2
source (``host.observers.sources.ros2``): the node's ``/NODE/transition_event`` topic (every
state it enters, whoever made the transition: seen at once) and the pseudo-topic
``/_lifecycle/NODE``, which delivers ``{"state": LABEL}`` from ``/NODE/get_state`` every
discovery period (``absent`` when the node is not in the graph), so that the state is known
without a transition and a node that dies is seen. A transitional state (``configuring``,
``activating``, ...) keeps what was said: the transition ends in a primary state. ``state``
is the last state seen.

``{heartbeat: TOPIC, timeout: S}``: ``HeartbeatObserver(node, topic, timeout)``, the bond of
Nav2's lifecycle manager with plain topics: the node publishes anything on ``TOPIC``
(``std_msgs/msg/Empty`` will do) more often than every ``timeout`` seconds (default 0.5);
``running(n)`` on each message, ``¬running(n)`` once ``timeout`` has passed without one (also
when none came within ``timeout`` of the observer's start). A hung node that stays in the
graph, with its process alive and its topics' silence not yet judged, is found within
``timeout``.
"""

from __future__ import annotations

from typing import Any

import host.atoms as A
from host.observers.base import DEFAULT_REFRESH, DEFAULT_VALIDITY
from host.observers.payload import TopicMessage
from host.observers.topics import TopicObserver

LIFECYCLE = "/_lifecycle/"  # = the ROS 2 source's pseudo-topic prefix (free of rclpy here)
PRIMARY = ("unconfigured", "inactive", "active", "finalized")
ABSENT = "absent"  # the source's word for a node not in the graph
DEFAULT_HEARTBEAT_TIMEOUT = 0.5


def transition_event_topic(node: str) -> str:
    return f"/{node}/transition_event"


class LifecycleObserver(TopicObserver):
    kind = "lifecycle"

    def __init__(self, node: str, *, name: str | None = None,
                 validity: float = DEFAULT_VALIDITY, refresh: float = DEFAULT_REFRESH) -> None:
        super().__init__(name or f"lifecycle:{node}", validity, refresh)
        self.node = node
        self.topics = (f"{LIFECYCLE}{node}", transition_event_topic(node))
        self.atom = str(A.running(node))
        self.state = "unknown"

    def atoms(self) -> list[str]:
        return [self.atom]

    def _feed(self, item: TopicMessage, now: float) -> None:
        state = _state(item.values)
        if state is None:
            return
        self.state = state
        if state in PRIMARY or state == ABSENT:
            self._say(self.atom, state == "active", now)


def _state(values: dict[str, Any] | None) -> str | None:
    """The state a message says: ``{"state": ...}`` of the pseudo-topic, or a
    ``TransitionEvent``'s goal state."""
    if not values:
        return None
    state = values.get("state")
    if isinstance(state, str):
        return state
    goal = values.get("goal_state")
    label = goal.get("label") if isinstance(goal, dict) else None
    return label if isinstance(label, str) and label else None


class HeartbeatObserver(TopicObserver):
    kind = "heartbeat"
    needs_input = False  # silence is the evidence

    def __init__(self, node: str, topic: str, timeout: float = DEFAULT_HEARTBEAT_TIMEOUT, *,
                 name: str | None = None, validity: float = DEFAULT_VALIDITY,
                 refresh: float = DEFAULT_REFRESH) -> None:
        super().__init__(name or f"heartbeat:{node}", validity, refresh)
        if timeout <= 0:
            raise ValueError(f"{self.name}: need timeout > 0")
        self.node = node
        self.topics = (topic,)
        self.timeout = timeout
        self.atom = str(A.running(node))
        self._last: float | None = None  # the last heartbeat, or the start

    def atoms(self) -> list[str]:
        return [self.atom]

    def _feed(self, item: TopicMessage, now: float) -> None:
        self._last = now
        self._say(self.atom, True, now)

    def _check(self, now: float) -> None:
        if self._last is None:
            self._last = now  # the start: the first heartbeat is due within timeout
        elif now >= self._last + self.timeout:
            self._say(self.atom, False, now)

    def _deadline(self) -> float | None:
        if self._last is None:
            return None
        if self.asserted.get(self.atom) is False:
            return None  # said; the refresh repeats it
        return self._last + self.timeout
