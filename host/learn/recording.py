"""What the learner saw of a robot: one value that the live watcher, a bag and a test all fill.

A ``Recording`` holds, over ``start``..``end`` (seconds on the source's clock: the wall clock of a
live robot, the bag's own clock for a bag), each topic's message type, arrival times and (stamped
types) header stamps, each node seen in the graph with the topics it publishes and subscribes and
whether it is a managed (lifecycle) node, each board channel's current readings (amperes) with its
name and whether it is protected, and what each probe saw (``ChannelProbe``: a channel switched
off for a while, and the topics that stopped and the nodes that left the graph meanwhile).
Nothing here does I/O; ``host.learn.infer`` turns a recording into a model.
"""

from __future__ import annotations

from dataclasses import dataclass, field


@dataclass(frozen=True)
class NodeSeen:
    """A node of the graph: its topics (as the graph says) and whether it is managed."""

    name: str
    publishes: tuple[str, ...] = ()
    subscribes: tuple[str, ...] = ()
    managed: bool = False


@dataclass(frozen=True)
class ChannelSeen:
    """A board channel: its name, whether the board protects it, its current readings (A)."""

    number: int
    name: str = ""
    protected: bool = False
    currents: tuple[float, ...] = ()


@dataclass(frozen=True)
class ChannelProbe:
    """Channel ``channel`` switched off from ``off`` to ``on`` (s): what stopped meanwhile."""

    channel: int
    off: float
    on: float
    stopped: tuple[str, ...] = ()  # topics with no message while it was off
    kept: tuple[str, ...] = ()  # topics that went on
    gone: tuple[str, ...] = ()  # nodes that left the graph
    lost: tuple[str, ...] = ()  # stopped topics that did not come back after it


@dataclass
class Recording:
    start: float
    end: float
    source: str = ""
    types: dict[str, str] = field(default_factory=dict)
    arrivals: dict[str, list[float]] = field(default_factory=dict)
    stamps: dict[str, list[tuple[float, float]]] = field(default_factory=dict)  # (arrival, stamp)
    nodes: dict[str, NodeSeen] = field(default_factory=dict)
    channels: dict[int, ChannelSeen] = field(default_factory=dict)
    probes: list[ChannelProbe] = field(default_factory=list)

    def add(self, topic: str, time: float, type_name: str = "",
            stamp: float | None = None) -> None:
        """One message of ``topic`` arrived at ``time`` (``stamp``: its header's stamp)."""
        self.arrivals.setdefault(topic, []).append(time)
        if stamp is not None:
            self.stamps.setdefault(topic, []).append((time, stamp))
        if type_name:
            self.types.setdefault(topic, type_name)

    @property
    def watched_until(self) -> float:
        """The end of the passive watch: the first probe's start, else ``end`` (rates are
        learned before it: a probe's silence, and a driver that stays down after its
        device's probe, are not the topic's rate)."""
        return min([p.off for p in self.probes] + [self.end])

    def watched(self, topic: str) -> list[float]:
        """The topic's arrivals during the passive watch."""
        until = self.watched_until
        return [t for t in self.arrivals.get(topic, []) if t < until]

    def sent_since(self, topic: str, since: float, recent: int = 200) -> int:
        """Messages of ``topic`` *sent* at ``since`` or later: for a stamped topic, those whose
        stamp, moved onto the arrivals' clock by the fastest delivery among the ``recent``
        latest, is that late (a busy receiver still delivers messages sent before a channel
        went off); else the arrivals."""
        pairs = self.stamps.get(topic)
        if pairs:
            shift = min(a - s for a, s in pairs[-recent:])
            return sum(1 for _, s in pairs if s + shift >= since)
        return sum(1 for t in self.arrivals.get(topic, ()) if t >= since)

    def watched_stamps(self, topic: str) -> list[float]:
        """The header stamps of the topic's messages that arrived during the passive watch."""
        until = self.watched_until
        return [s for t, s in self.stamps.get(topic, []) if t < until]
