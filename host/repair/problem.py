"""The repair problem from a diagnosis (paper 000 §IV-E): objects, I and G.

``RepairModel`` is what planning needs to know about a robot: each component's PDDL type
(``switchable`` for SH, ``hardware`` for H, ``driver`` for SN, ``node`` for N and HN), what
each node needs working (its hardware, the publishers of its input topics) and which objects
are protected. ``repair_model(system)`` is the adapter from the diagnosis package's
``SystemModel``; tests and benchmarks build a ``RepairModel`` directly. ``build_problem``
makes the problem of one diagnosis: I = the observations + AB(c) for the bad + ~AB(c) for
the good, G = ~AB(c) for all c. Where no observation says whether a device is powered or a
node runs, the paper's model decides (a healthy device is on, a healthy node runs) and for a
bad one a default that keeps the plan safe (a bad device is off: power it up; a bad node
runs: restart it); every such assumption is listed in ``RepairProblem.assumed``.
``to_pddl`` writes the problem file, for Fast Downward and for a person to read.
"""

from __future__ import annotations

import logging
import re
from collections.abc import Iterable, Mapping
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

from host.repair.domain import Atom
from host.repair.errors import ProblemError

if TYPE_CHECKING:
    from host.diagnosis.logic import Literal
    from host.diagnosis.model import SystemModel

log = logging.getLogger(__name__)

# the domain's vocabulary (models/*/repair.pddl)
AB, ON, RUNNING, NEEDS, PROTECTED = "ab", "on", "running", "needs", "protected"
MANAGED = "managed"  # static: a ROS 2 managed (lifecycle) node, repaired by reconfigure_node
SWITCHABLE, HARDWARE, DRIVER, NODE = "switchable", "hardware", "driver", "node"
NODE_TYPES = frozenset({DRIVER, NODE})
_KIND_TYPE = {"SH": SWITCHABLE, "H": HARDWARE, "SN": DRIVER, "HN": NODE, "N": NODE}
_PDDL_NAME = re.compile(r"^[A-Za-z][A-Za-z0-9_\-]*$")


@dataclass(frozen=True)
class RepairModel:
    """A robot as the planner sees it. ``types`` keeps the model's order."""

    name: str
    types: Mapping[str, str]
    needs: Mapping[str, tuple[str, ...]] = field(default_factory=dict)
    protected: frozenset[str] = frozenset()
    managed: frozenset[str] = frozenset()

    def objects(self) -> dict[str, str]:
        return dict(self.types)

    def static_facts(self) -> list[Atom]:
        out = [Atom(NEEDS, (n, c)) for n, cs in self.needs.items() for c in cs]
        out += [Atom(PROTECTED, (c,)) for c in sorted(self.protected)]
        out += [Atom(MANAGED, (n,)) for n in sorted(self.managed)]
        return out

    def is_node(self, name: str) -> bool:
        return self.types.get(name) in NODE_TYPES


def protected_channel_object(channel: int) -> str:
    return f"channel{channel}"


def repair_model(system: SystemModel, managed: Iterable[str] = ()) -> RepairModel:
    """Adapter from ``host.diagnosis.model.SystemModel``; ``managed``: the nodes that are ROS 2
    managed (lifecycle) nodes on this robot (``(managed n)``, for ``reconfigure_node``).

    A node needs its hardware and the publishers of the topics its outputs depend on (of the
    topics it reads, if it publishes nothing). Nodes that need each
    other in a cycle could never be started (each waits for the other), so dependencies inside
    a cycle are dropped (the executor's verification waits for the cycle as a whole). Each
    protected board channel becomes a protected ``switchable`` object that is on and healthy,
    so no domain, however written, can plan to switch it off.
    """
    types = {c.name: _KIND_TYPE[c.kind.value] for c in system.components.values()}
    publishers: dict[str, list[str]] = {}
    for c in system.components.values():
        for t in c.publishes:
            publishers.setdefault(t, []).append(c.name)
    needs: dict[str, tuple[str, ...]] = {}
    for c in system.components.values():
        if not c.is_node:
            continue
        # the inputs its outputs depend on; a node without outputs (a viewer) needs what it reads
        if c.publishes:
            inputs = [i for ins in c.publishes.values() for i in ins]
        else:
            inputs = list(c.subscribes)
        deps = [*c.hardware, *(p for t in inputs for p in publishers.get(t, ()))]
        needs[c.name] = tuple(d for d in dict.fromkeys(deps) if d != c.name)
    needs = _drop_cycles(needs)
    protected = {c.name for c in system.components.values() if c.channel in system.protected}
    for ch in sorted(system.protected):
        if system.device_on_channel(ch) is None:
            name = protected_channel_object(ch)
            types[name] = SWITCHABLE
            protected.add(name)
    return RepairModel(system.name, types, needs, frozenset(protected),
                       frozenset(n for n in managed if types.get(n) in NODE_TYPES))


def _drop_cycles(needs: dict[str, tuple[str, ...]]) -> dict[str, tuple[str, ...]]:
    """Remove the node->node dependencies that lie on a cycle (Tarjan's SCCs)."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    comp: dict[str, int] = {}
    stack: list[str] = []
    counter = [0]

    def visit(v: str) -> None:  # recursion depth = longest dependency chain
        index[v] = low[v] = counter[0]
        counter[0] += 1
        stack.append(v)
        for w in needs.get(v, ()):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w not in comp:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            while True:
                w = stack.pop()
                comp[w] = index[v]
                if w == v:
                    break

    for v in needs:
        if v not in index:
            visit(v)
    return {n: tuple(d for d in ds if comp.get(d, -1) != comp[n]) for n, ds in needs.items()}


@dataclass(frozen=True)
class RepairProblem:
    """I and G for one diagnosis: ``init`` holds the true fluent atoms (closed world)."""

    model: RepairModel
    bad: frozenset[str]
    init: frozenset[Atom]
    goal: tuple[Atom, ...]  # each must be false: (not (ab c))
    assumed: tuple[str, ...] = ()
    ignored: tuple[str, ...] = ()


def build_problem(
    model: RepairModel, bad: Iterable[str], observations: Iterable[Literal] = ()
) -> RepairProblem:
    """The planning problem of the diagnosis ``bad`` under ``observations``."""
    bad_set = frozenset(bad)
    unknown = sorted(bad_set - set(model.types))
    if unknown:
        raise ProblemError(
            f"unknown component(s) in the diagnosis: {', '.join(unknown)}",
            f"use names from the model {model.name!r}: {', '.join(list(model.types)[:12])}...",
        )
    observed: dict[tuple[str, str], bool] = {}
    ignored: list[str] = []
    for o in observations:
        pred, args = split_atom(o.atom)
        if pred in (ON, RUNNING) and len(args) == 1 and args[0] in model.types:
            observed[(pred, args[0])] = o.positive
        elif pred.lower() == AB:
            raise ProblemError(
                f"the observation {o} states a health atom",
                "health comes from the diagnosis (--bad), not from observations",
            )
        else:
            ignored.append(str(o))
    init: set[Atom] = set()
    assumed: list[str] = []
    for name, typ in model.types.items():
        is_bad = name in bad_set
        if is_bad:
            init.add(Atom(AB, (name,)))
        fluent = ON if typ == SWITCHABLE else RUNNING if typ in NODE_TYPES else None
        if fluent is None:
            continue
        value = observed.get((fluent, name))
        if value is None:
            # healthy: the model's clauses say on / running; bad: off (power it up) for a
            # device, running (restart it: safe either way) for a node
            value = not is_bad if fluent == ON else True
            if is_bad:
                assumed.append(f"{'' if value else '~'}{fluent}({name})")
        if value:
            init.add(Atom(fluent, (name,)))
    goal = tuple(Atom(AB, (name,)) for name in model.types)
    if ignored:
        log.debug("observations not in the repair domain, ignored: %s", ignored)
    return RepairProblem(model, bad_set, frozenset(init), goal, tuple(assumed), tuple(ignored))


def split_atom(atom: str) -> tuple[str, tuple[str, ...]]:
    """``on(jaguar)`` -> ``("on", ("jaguar",))``."""
    if "(" not in atom:
        return atom, ()
    pred, rest = atom.split("(", 1)
    inner = rest.rstrip(")")
    return pred, tuple(a.strip() for a in inner.split(",") if a.strip())


def to_pddl(problem: RepairProblem, domain_name: str, name: str = "repair") -> str:
    """The problem as a PDDL file (objects by type, I, G)."""
    bad_names = [n for n in problem.model.types if not _PDDL_NAME.match(n)]
    if bad_names:
        raise ProblemError(
            f"component name(s) {', '.join(bad_names[:5])} are not valid PDDL names",
            "use letters, digits, '_' and '-', starting with a letter",
        )
    by_type: dict[str, list[str]] = {}
    for obj, typ in problem.model.types.items():
        by_type.setdefault(typ, []).append(obj)
    lines = [f"(define (problem {name})", f"  (:domain {domain_name})", "  (:objects"]
    for typ, objs in by_type.items():
        lines.append(f"    {' '.join(objs)} - {typ}")
    lines.append("  )")
    lines.append("  (:init")
    facts = [*problem.model.static_facts(), *sorted(problem.init, key=str)]
    lines.extend(f"    ({a.pred} {' '.join(a.args)})" for a in facts)
    lines.append("  )")
    goals = " ".join(f"(not ({a.pred} {' '.join(a.args)}))" for a in problem.goal)
    lines.append(f"  (:goal (and {goals})))")
    return "\n".join(lines) + "\n"
