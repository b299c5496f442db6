"""From a ``Recording`` to a ``LearnedModel``: components, topics, dependencies, devices.

The rules, each leaving its evidence beside what it decided (``host.learn.render`` writes it as
comments for the person who reviews the model):

- *topics*: every topic some node publishes or that carried messages, but ROS 2's own
  (``/rosout``, ``/parameter_events``, ``.../transition_event``, and the status plumbing
  ``/diagnostics``, ``/diagnostics_agg``, ``/diagnostics_toplevel_state``: many nodes publish
  there, so its rate is theirs summed and no one node's output) and dxboard's (``/dxboard/...``);
  its type, its rate evidence and proposed observer (``host.learn.stats``) from the passive
  watch, never from a probe's time.
- *nodes*: every node of the graph with the topics it publishes and subscribes, managed when it
  offers the lifecycle services. A topic nobody in the graph publishes (a bag without the
  graph, Zenoh) gets a node ``publisher_of_<topic>`` to rename.
- *dependencies*: an output depends on every input of its node (who subscribes to what), less
  the inputs a probe silenced while the output went on. Which outputs follow which inputs *in
  time* (the lag from the input's latest message is steady: published in answer to it) is
  measured and noted; a timer that stops when its inputs go stale does not show in time, so
  timing alone never removes a dependency.
- *probes*: a topic too slow to send ``MIN_EXPECTED`` messages while its channel was off (a
  0.5 Hz map in a 1.5 s probe) is not judged stopped by it: its silence is no evidence; a
  message it sent meanwhile still shows that it went on.
- *devices* (``--probe``): a channel whose switching off stopped topics or nodes powers a
  device (switchable hardware, named after the channel); its drivers are the nodes that left
  the graph, or whose outputs stopped while none of their inputs did. Without a probe, a
  channel drawing current is a device with no known driver. A protected channel never is one.
- *current bands*: from the channel's readings while on, widened by ``BAND_MARGIN``.
"""

from __future__ import annotations

import bisect
import math
import re
from dataclasses import dataclass, field, replace

from host.learn.recording import ChannelProbe, Recording
from host.learn.stats import RateEvidence, RateProposal, learn_rate, propose

IGNORED = re.compile(r"^/(rosout|parameter_events|diagnostics(_agg|_toplevel_state)?)$"
                     r"|/transition_event$|^/dxboard(/|$)")
NOISE_A = 0.01  # a channel drawing less than this powers nothing
BAND_MARGIN = 0.3  # the band is the readings' range widened by this share at each end
MIN_LAGS = 5
FOLLOW_SPREAD = 0.2  # lag stddev below this share of the input's period: follows it
MIN_EXPECTED = 3.0  # a probe judges a topic stopped only when it expected this many messages


@dataclass(frozen=True)
class Lag:
    """How ``output`` trails ``input`` in time: ``n`` lags, their mean and stddev (s)."""

    n: int
    mean: float
    stddev: float
    follows: bool


@dataclass(frozen=True)
class LearnedTopic:
    name: str
    type: str
    publishers: tuple[str, ...]
    evidence: RateEvidence | None
    proposal: RateProposal | None


@dataclass
class LearnedNode:
    name: str
    managed: bool = False
    hardware: tuple[str, ...] = ()
    subscribes: tuple[str, ...] = ()
    publishes: dict[str, tuple[str, ...]] = field(default_factory=dict)
    notes: dict[str, list[str]] = field(default_factory=dict)  # output -> evidence
    guessed: bool = False  # named after its topic: nobody in the graph publishes it

    @property
    def kind(self) -> str:
        return "SN" if self.hardware else "N"


@dataclass(frozen=True)
class LearnedDevice:
    name: str
    channel: int
    band: tuple[float, float] | None
    n: int  # readings behind the band
    low: float
    high: float
    probe: ChannelProbe | None


@dataclass
class LearnedModel:
    robot: str
    source: str
    span: float
    ros2: bool
    topics: list[LearnedTopic]
    nodes: list[LearnedNode]
    devices: list[LearnedDevice]
    channels: int = 0
    protected: tuple[int, ...] = ()
    idle: tuple[int, ...] = ()  # channels that drew no current and stopped nothing
    loads: tuple[LearnedDevice, ...] = ()  # drew current, but their probe stopped nothing


def topic_names(rec: Recording) -> list[str]:
    names = set(rec.arrivals) | {t for n in rec.nodes.values() for t in n.publishes}
    return sorted(t for t in names if not IGNORED.search(t))


def lag(output: list[float], inputs: list[float], input_rate: float) -> Lag | None:
    """The lags of ``output``'s messages behind ``input``'s latest one before each."""
    if not inputs or input_rate <= 0:
        return None
    period = 1.0 / input_rate
    lags = []
    for t in output:
        i = bisect.bisect_right(inputs, t) - 1
        if i >= 0 and t - inputs[i] <= 2 * period:
            lags.append(t - inputs[i])
    if len(lags) < MIN_LAGS:
        return None
    mean = sum(lags) / len(lags)
    sd = math.sqrt(sum((x - mean) ** 2 for x in lags) / len(lags))
    return Lag(len(lags), mean, sd, sd < FOLLOW_SPREAD * period and mean < 0.5 * period)


def _safe(topic: str) -> str:
    return "publisher_of_" + (re.sub(r"\W+", "_", topic).strip("_") or "topic")


def infer(rec: Recording, robot: str, ros2: bool = True) -> LearnedModel:
    """The model a recording supports (see the module's rules)."""
    topics = topic_names(rec)
    nodes: dict[str, LearnedNode] = {}
    for seen in sorted(rec.nodes.values(), key=lambda n: n.name):
        pubs = tuple(t for t in seen.publishes if t in topics)
        subs = tuple(t for t in seen.subscribes if not IGNORED.search(t))
        nodes[seen.name] = LearnedNode(seen.name, seen.managed, subscribes=subs,
                                       publishes={t: subs for t in pubs})
    publishers = {t: tuple(n.name for n in nodes.values() if t in n.publishes) for t in topics}
    for t in topics:
        if not publishers[t]:
            name = _safe(t)
            nodes[name] = LearnedNode(name, publishes={t: ()}, guessed=True)
            publishers[t] = (name,)
    learned = []
    for t in topics:
        ev = learn_rate(rec.watched(t), rec.watched_stamps(t))
        learned.append(LearnedTopic(t, rec.types.get(t, ""), publishers[t], ev,
                                    propose(ev) if ev else None))
    rates = {lt.name: lt.evidence.rate for lt in learned if lt.evidence}
    _timing(rec, nodes, rates)
    rec = replace(rec, probes=[_judged(p, rates) for p in rec.probes])
    found = _devices(rec, nodes)
    loads = tuple(d for d in found if _unneeded(d))
    devices = [d for d in found if not _unneeded(d)]
    _probe_dependencies(rec, nodes)
    used = {d.channel for d in found}
    idle = tuple(c for c, ch in sorted(rec.channels.items())
                 if c not in used and not ch.protected)
    return LearnedModel(robot, rec.source, rec.watched_until - rec.start, ros2, learned,
                        list(nodes.values()), devices, len(rec.channels),
                        tuple(c for c, ch in sorted(rec.channels.items()) if ch.protected), idle,
                        loads)


def _unneeded(d: LearnedDevice) -> bool:
    """A load its probe showed nothing observed needs: no topic stopped, no node left."""
    return d.probe is not None and not d.probe.stopped and not d.probe.gone


def _judged(p: ChannelProbe, rates: dict[str, float]) -> ChannelProbe:
    """``p`` less the stopped topics too slow for its window (see the module)."""
    window = p.on - p.off
    stopped = tuple(t for t in p.stopped if t not in rates or rates[t] * window >= MIN_EXPECTED)
    return replace(p, stopped=stopped, lost=tuple(t for t in p.lost if t in stopped))


def _timing(rec: Recording, nodes: dict[str, LearnedNode], rates: dict[str, float]) -> None:
    for node in nodes.values():
        for out in node.publishes:
            for inp in node.subscribes:
                lg = lag(rec.watched(out), sorted(rec.watched(inp)), rates.get(inp, 0.0))
                if lg is None:
                    continue
                how = "follows" if lg.follows else "no steady lag behind"
                node.notes.setdefault(out, []).append(
                    f"{how} {inp} (lag {lg.mean * 1000:.1f} ms sd {lg.stddev * 1000:.1f}, "
                    f"n={lg.n})")


def _probe_dependencies(rec: Recording, nodes: dict[str, LearnedNode]) -> None:
    for node in nodes.values():
        for out, inputs in list(node.publishes.items()):
            keep = list(inputs)
            for p in rec.probes:
                for inp in inputs:
                    if inp in p.stopped and out in p.kept and inp in keep:
                        keep.remove(inp)
                        node.notes.setdefault(out, []).append(
                            f"probe of channel {p.channel}: {inp} stopped, {out} went on: "
                            f"not a dependency")
                    elif inp in p.stopped and out in p.stopped:
                        node.notes.setdefault(out, []).append(
                            f"probe of channel {p.channel}: stopped with {inp}")
            node.publishes[out] = tuple(keep)


def _band(currents: tuple[float, ...]) -> tuple[float, float] | None:
    if not currents or max(currents) < NOISE_A:
        return None
    lo, hi = min(currents), max(currents)
    width = max(hi - lo, 0.1 * hi)
    return (round(max(NOISE_A, lo - BAND_MARGIN * width - 0.2 * lo), 3),
            round(hi + BAND_MARGIN * width + 0.2 * hi, 3))


def _device_name(rec: Recording, channel: int, nodes: dict[str, LearnedNode]) -> str:
    name = re.sub(r"\W+", "_", rec.channels[channel].name).strip("_") \
        if channel in rec.channels else ""
    if not name or name in nodes or not name[0].isalpha():
        name = f"device{channel}"
    return name


def _devices(rec: Recording, nodes: dict[str, LearnedNode]) -> list[LearnedDevice]:
    probes = {p.channel: p for p in rec.probes}
    out = []
    for c in sorted(set(rec.channels) | set(probes)):
        ch = rec.channels.get(c)
        if ch is not None and ch.protected:
            continue
        currents = ch.currents if ch is not None else ()
        band = _band(currents)
        p = probes.get(c)
        drivers = _drivers(p, nodes) if p is not None else []
        if band is None and not drivers and not (p is not None and p.stopped):
            continue
        name = _device_name(rec, c, nodes)
        for d in drivers:
            nodes[d].hardware = (*nodes[d].hardware, name)
        out.append(LearnedDevice(name, c, band, len(currents), min(currents, default=0.0),
                                 max(currents, default=0.0), p))
    return out


def _drivers(p: ChannelProbe, nodes: dict[str, LearnedNode]) -> list[str]:
    """The nodes a probe shows to drive its channel's device: gone from the graph, or
    publishing a topic that stopped while none of their inputs did."""
    stopped = set(p.stopped)
    found = []
    for n in nodes.values():
        silenced = any(t in stopped for t in n.publishes)
        fed = any(t in stopped for t in n.subscribes)
        if n.name in p.gone or (silenced and not fed):
            found.append(n.name)
    return found
