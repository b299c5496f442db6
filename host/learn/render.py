"""A ``LearnedModel`` as the ``system.yaml`` a person reviews: every learned item with its evidence.

The file is plain ``system.yaml`` (``host.diagnosis.model``, ``host.observers.config``,
``host.repair.external``) and loads with ``dxboard model check``; the evidence is in YAML
comments, which every loader ignores, at the end of the line it backs or on the lines before
it: ``n`` (messages, readings), the spread (the per-window rate's standard deviation, the
periods' coefficient of variation, the largest gap), the lags behind inputs, what each probe
stopped. Items the learner could not decide are comments too (a reactive topic's observer, a
node named after its topic), so the review starts from them.
"""

from __future__ import annotations

from collections.abc import Iterable

from host.learn.infer import LearnedDevice, LearnedModel, LearnedNode, LearnedTopic
from host.learn.stats import RateEvidence


def _flow(items: Iterable[str]) -> str:
    return "[" + ", ".join(items) + "]"


def _num(x: float) -> str:
    return f"{x:g}"


def rate_evidence(ev: RateEvidence) -> str:
    """One line of a topic's rate evidence."""
    kind = "periodic" if ev.periodic else "reactive"
    return (f"n={ev.n} over {ev.span:.1f} s: {ev.rate:.3g} Hz ({ev.clock} clock), spread "
            f"{ev.spread:.2g} Hz over {ev.windows} windows, cv {ev.cv:.2f}, "
            f"largest gap {ev.max_period * ev.rate:.1f} periods: {kind}")


def _device(d: LearnedDevice, drivers: list[str]) -> list[str]:
    lines = [f"  {d.name}:", "    kind: SH", f"    channel: {d.channel}"]
    if d.band is not None:
        lines.append(f"    current: [{_num(d.band[0])}, {_num(d.band[1])}]  # n={d.n} "
                     f"readings from {d.low:.3f} to {d.high:.3f} A, widened")
    else:
        lines.append("    # current: no readings (learned without --board): give its band")
    if d.probe is not None:
        p = d.probe
        lines.append(f"    # probe: channel {p.channel} off {p.on - p.off:.1f} s stopped "
                     f"{_flow(p.stopped) if p.stopped else 'no topic'}"
                     + (f", nodes gone {_flow(p.gone)}" if p.gone else "")
                     + f"; drivers: {_flow(drivers) if drivers else 'none found'}"
                     + (f"; {_flow(p.lost)} did not come back" if p.lost else ""))
    return lines


def _load(d: LearnedDevice) -> str:
    band = (f", current: [{_num(d.band[0])}, {_num(d.band[1])}]" if d.band is not None else "")
    return (f"  #   {d.name}: {{kind: SH, channel: {d.channel}{band}}}  # n={d.n} readings from "
            f"{d.low:.3f} to {d.high:.3f} A")


def _node(n: LearnedNode) -> list[str]:
    managed = "  # a managed (lifecycle) node" if n.managed else ""
    lines = [f"  {n.name}:{managed}"]
    if n.guessed:
        lines.append("    # no node in the graph publishes this topic: rename to its node")
    elif not n.subscribes and n.publishes and not n.hardware:
        lines.append("    # publishes without inputs: if it reads a device, make it HN "
                     "with hardware: [that device]")
    lines.append(f"    kind: {n.kind}")
    if n.hardware:
        lines.append(f"    hardware: {_flow(n.hardware)}  # its channel's probe stopped it")
    if n.subscribes:
        lines.append(f"    subscribes: {_flow(n.subscribes)}")
    if n.publishes:
        lines.append("    publishes:")
        for out, inputs in n.publishes.items():
            lines.append(f"      {out}: {_flow(inputs)}")
            lines.extend(f"      # {note}" for note in n.notes.get(out, []))
    return lines


def _topic(t: LearnedTopic) -> list[str]:
    ev, p = t.evidence, t.proposal
    kind = t.type or "type unknown"
    if ev is None:
        return [f"    # {t.name} ({kind}): fewer than 5 messages seen: no rate observer"]
    if p is None:
        return [f"    # {t.name} ({kind}): {rate_evidence(ev)}: no rate observer"]
    return [f"    {t.name}: {{rate: {_num(p.rate)}, tolerance: {_num(p.tolerance)}, "
            f"window: {_num(p.window)}, silence: {_num(p.silence)}}}",
            f"    # {kind}; {rate_evidence(ev)}"]


def render(m: LearnedModel) -> str:
    """The learned model as ``system.yaml`` text."""
    out = [f"# Learned by dxboard model learn from {m.source} over {m.span:.1f} s: review it.",
           "# Every learned item carries its evidence in comments (n, spread, lags, probes).",
           f"robot: {m.robot}"]
    if m.channels:
        out += ["board:", f"  channels: {m.channels}"]
        if m.protected:
            out.append(f"  protected: {_flow(str(c) for c in m.protected)}  # never probed")
        if m.idle:
            out.append(f"  # idle channels (no current, stopped nothing): "
                       f"{_flow(str(c) for c in m.idle)}")
    out.append("")
    out.append("components:")
    nodes = {n.name: n for n in m.nodes}
    for d in m.devices:
        out += _device(d, [n.name for n in m.nodes if d.name in n.hardware])
    for n in nodes.values():
        out += _node(n)
    if m.loads:
        out.append("  # loads: they draw current, but their probe stopped no topic and no node, so "
                   "no observation")
        out.append("  # depends on them; uncomment one to watch its current band and repair "
                   "its power:")
        out += [_load(d) for d in m.loads]
    out += ["", "observers:"]
    if m.ros2:
        out.append("  source: {kind: ros2}")
    if m.devices:
        out.append("  hardware: {link_timeout: 0.25, settle: 3}")
    real = [n for n in m.nodes if not n.guessed]
    if m.ros2 and real:
        out.append("  nodes:  # present in the ROS 2 graph")
        out += [f"    {n.name}: {{graph: true}}" for n in real]
    if m.topics:
        out.append("  topics:  # rate and tolerance in Hz, window in s, silence in periods")
        for t in m.topics:
            out += _topic(t)
    if real:
        out += ["", "# Started elsewhere: give each a restart actuator (systemd: UNIT, "
                "command: [argv] or container: NAME)", "external:"]
        out += [f"  {n.name}: {{lifecycle: true}}" if n.managed and m.ros2
                else f"  {n.name}: {{}}" for n in real]
    return "\n".join(out) + "\n"
