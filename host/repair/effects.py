"""The observable effect of each repair action, and how long it takes to settle.

The domain's effects name planning atoms (``on(d)``, ``running(n)``, ``ab(c)``); the executor
can only verify what observers report. ``expected_effects(step, model)`` maps a step to the
observation literals that must hold once it has worked:

==================  ==========================================================================
``power_up(d)``     ``on(d)``, and ``in_band(d)`` (its current in band) when ``d`` has a band
``power_cycle(d)``  the same, after the off time
``shutdown(d)``     ``~on(d)``
``start_node(n)``   ``running(n)``, and ``ok(t)`` for every topic ``t`` that ``n`` publishes
``reconfigure_n…``  the same (``reconfigure_node(n)``: a managed node's lifecycle transitions)
``stop_node(n)``    ``~running(n)``
==================  ==========================================================================

``kept(step)`` are the expected literals the step does not change but keeps: ``running(n)`` of
a ``reconfigure_node`` (the same process throughout). They must still hold when the rest is
seen, not be observed anew: a steady process is reported again only at its observer's next
refresh, up to a second later, for nothing.

Only atoms some observer actually reports are expected (``observable``; None: all): a topic no
observer watches cannot be verified, and waiting for it would fail every repair. The effect is
checked in observations made at least ``settle`` seconds after the step ended — the device's
boot time or the node's ``settle_s`` — so a node that starts and dies at once, or a device
that comes on and trips, does not pass. ``contradictions(step)`` are the literals that end the
wait at once as a failure (the board tripped the channel the step switched on: no use waiting
out the boot time). Nothing here is specific to one robot: all comes from
the ``SystemModel`` and the ``processes:`` section.
"""

from __future__ import annotations

from collections.abc import Collection, Mapping
from typing import TYPE_CHECKING

import host.atoms as A

if TYPE_CHECKING:
    from host.diagnosis.model import SystemModel
    from host.planning.plan import Step
    from host.repair.processes import ProcessConfig

DEFAULT_DEVICE_SETTLE_S = 1.0
DEFAULT_NODE_SETTLE_S = 2.0
#: actions whose effect is immediate (no settling: a stopped process or a switched-off
#: channel is seen at once)
IMMEDIATE = frozenset({"shutdown", "stop_node"})


def expected_effects(step: Step, model: SystemModel,
                     observable: Collection[str] | None = None) -> dict[str, bool]:
    """The literals (atom -> value) that show ``step`` worked (see the module docstring)."""
    if not step.args:
        return {}
    name = step.args[0]
    comp = model.components.get(name)
    out: dict[str, bool] = {}
    if step.action in ("power_up", "power_cycle"):
        out[str(A.on(name))] = True
        if comp is not None and comp.current is not None:
            out[str(A.in_band(name))] = True
    elif step.action == "shutdown":
        out[str(A.on(name))] = False
    elif step.action in ("start_node", "reconfigure_node"):
        out[str(A.running(name))] = True
        if comp is not None:
            for topic in comp.publishes:
                out[str(A.ok(topic))] = True
    elif step.action == "stop_node":
        out[str(A.running(name))] = False
    if observable is not None:
        out = {a: v for a, v in out.items() if a in observable}
    return out


def kept(step: Step) -> frozenset[str]:
    """The expected literals ``step`` keeps rather than brings about (see the module
    docstring): checked for their value, whenever observed."""
    if step.action == "reconfigure_node" and step.args:
        return frozenset({str(A.running(step.args[0]))})
    return frozenset()


def contradictions(step: Step, observable: Collection[str] | None = None) -> dict[str, bool]:
    """Literals that, once observed after ``step``, mean it failed and waiting is pointless:
    the board tripped or latched the channel it switched on."""
    if step.action not in ("power_up", "power_cycle") or not step.args:
        return {}
    atom = str(A.tripped(step.args[0]))
    return {atom: True} if observable is None or atom in observable else {}


def settle_times(model: SystemModel, processes: Mapping[str, ProcessConfig] | None = None,
                 devices: Mapping[str, float] | None = None,
                 device_default: float = DEFAULT_DEVICE_SETTLE_S,
                 node_default: float = DEFAULT_NODE_SETTLE_S) -> dict[str, float]:
    """Settle time per component: nodes from ``processes`` (``settle_s``), devices from
    ``devices`` (their boot times), else the defaults."""
    out: dict[str, float] = {}
    for c in model.components.values():
        if c.is_node:
            cfg = (processes or {}).get(c.name)
            out[c.name] = cfg.settle_s if cfg is not None else node_default
        elif c.channel is not None:
            out[c.name] = (devices or {}).get(c.name, device_default)
    return out
