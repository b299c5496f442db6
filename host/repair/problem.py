"""The repair problem from a diagnosis (paper 000 §IV-E): objects, I and G.

``RepairModel`` is what planning needs to know about a robot: each component's PDDL type
(``switchable`` for SH, ``hardware`` for H, ``driver`` for SN, ``node`` for N and HN), what
each node needs working (its hardware, the publishers of its input topics) and which objects
are protected. ``repair_model(system)`` is the adapter from the diagnosis package's
``SystemModel`` (``theory_model.py`` builds one from a tug model); tests and benchmarks build
a ``RepairModel`` directly. ``build_problem`` makes the problem of one diagnosis in the
domain's own words (``vocabulary.Vocabulary``): I = the observations + AB(c) for the bad +
~AB(c) for the good, G = ~AB(c) for all c, where "AB(c)" is ``(ab c)`` in our domain and
``(bad c)`` / ``(good c)`` in the original's, and a false fact is either absent (closed world)
or the domain's explicit complement (``(not_on c)``). Where no observation says whether a
device is powered or a node runs, the paper's model decides (a healthy device is on, a
healthy node runs) and for a bad one a default that keeps the plan safe (a bad device is off:
power it up; a bad node runs: restart it); every such assumption is listed in
``RepairProblem.assumed``. A model type the domain lacks falls back to the nearest one it has
(``domain_type``: a driver is a node, a switchable device is hardware). ``to_pddl`` writes the
problem file, for Fast Downward and for a person to read.
"""

from __future__ import annotations

import logging
import re
from collections.abc import Collection, Iterable, Mapping
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

from host.planning.domain import ROOT_TYPE, PddlAtom
from host.planning.errors import ProblemError
from host.planning.vocabulary import (
    ABNORMAL,
    POWERED,
    ROLE_OF_OBSERVATION,
    RUNNING,
    Vocabulary,
)

if TYPE_CHECKING:
    from host.diagnosis.logic import Literal
    from host.diagnosis.model import SystemModel

log = logging.getLogger(__name__)

# the static predicates the problem layer writes (when the domain declares them)
NEEDS, PROTECTED = "needs", "protected"
MANAGED = "managed"  # static: a ROS 2 managed (lifecycle) node, repaired by reconfigure_node
EXTERNAL, RESTARTABLE = "external", "restartable"  # static: started elsewhere; has an actuator
SWITCHABLE, HARDWARE, DRIVER, NODE, COMPONENT = "switchable", "hardware", "driver", "node", \
    "component"
NODE_TYPES = frozenset({DRIVER, NODE})
_KIND_TYPE = {"SH": SWITCHABLE, "H": HARDWARE, "SN": DRIVER, "HN": NODE, "N": NODE}
#: a model type, then what stands for it in a domain that lacks it (``software``: the
#: original's name for nodes)
TYPE_FALLBACK: Mapping[str, tuple[str, ...]] = {
    SWITCHABLE: (SWITCHABLE, HARDWARE, COMPONENT),
    HARDWARE: (HARDWARE, COMPONENT),
    DRIVER: (DRIVER, NODE, "software", COMPONENT),
    NODE: (NODE, "software", COMPONENT),
    COMPONENT: (COMPONENT,),
}


def domain_type(model_type: str, declared: Collection[str]) -> str:
    """The domain's type for an object of ``model_type`` (``object`` if none fits)."""
    for t in TYPE_FALLBACK.get(model_type, (model_type,)):
        if t in declared:
            return t
    return ROOT_TYPE
_PDDL_NAME = re.compile(r"^[A-Za-z][A-Za-z0-9_\-]*$")


@dataclass(frozen=True)
class RepairModel:
    """A robot as the planner sees it. ``types`` keeps the model's order."""

    name: str
    types: Mapping[str, str]
    needs: Mapping[str, tuple[str, ...]] = field(default_factory=dict)
    protected: frozenset[str] = frozenset()
    managed: frozenset[str] = frozenset()
    external: frozenset[str] = frozenset()  # nodes started elsewhere (host.repair.external)
    restartable: frozenset[str] = frozenset()  # of those, the ones an actuator restarts

    def objects(self) -> dict[str, str]:
        return dict(self.types)

    def static_facts(self) -> list[PddlAtom]:
        out = [PddlAtom(NEEDS, (n, c)) for n, cs in self.needs.items() for c in cs]
        out += [PddlAtom(PROTECTED, (c,)) for c in sorted(self.protected)]
        out += [PddlAtom(MANAGED, (n,)) for n in sorted(self.managed)]
        out += [PddlAtom(EXTERNAL, (n,)) for n in sorted(self.external)]
        out += [PddlAtom(RESTARTABLE, (n,)) for n in sorted(self.restartable)]
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
    needs = drop_cycles(needs)
    protected = {c.name for c in system.components.values() if c.channel in system.protected}
    for ch in sorted(system.protected):
        if system.device_on_channel(ch) is None:
            name = protected_channel_object(ch)
            types[name] = SWITCHABLE
            protected.add(name)
    return RepairModel(system.name, types, needs, frozenset(protected),
                       frozenset(n for n in managed if types.get(n) in NODE_TYPES))


def drop_cycles(needs: dict[str, tuple[str, ...]]) -> dict[str, tuple[str, ...]]:
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
    init: frozenset[PddlAtom]
    goal: tuple[PddlAtom, ...]  # each must hold (goal_holds) or be false: (good c) / (not (ab c))
    assumed: tuple[str, ...] = ()
    ignored: tuple[str, ...] = ()
    goal_holds: bool = False


def build_problem(
    model: RepairModel, bad: Iterable[str], observations: Iterable[Literal] = (),
    vocabulary: Vocabulary | None = None,
) -> RepairProblem:
    """The planning problem of the diagnosis ``bad`` under ``observations``, in the words of
    ``vocabulary`` (default: ours, ``ab`` / ``on`` / ``running``)."""
    words = Vocabulary() if vocabulary is None else vocabulary
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
        role = ROLE_OF_OBSERVATION.get(pred)
        if role is not None and len(args) == 1 and args[0] in model.types:
            observed[(role, args[0])] = o.positive
        elif pred.lower() == "ab":
            raise ProblemError(
                f"the observation {o} states a health atom",
                "health comes from the diagnosis (--bad), not from observations",
            )
        else:
            ignored.append(str(o))
    init: set[PddlAtom] = set()
    assumed: list[str] = []
    for name, typ in model.types.items():
        is_bad = name in bad_set
        init.update(PddlAtom(p, (o,)) for p, o in words.facts(ABNORMAL, name, is_bad))
        role = POWERED if typ == SWITCHABLE else RUNNING if typ in NODE_TYPES else None
        if role is None:
            continue
        value = observed.get((role, name))
        if value is None:
            # healthy: the model's clauses say on / running; bad: off (power it up) for a
            # device, running (restart it: safe either way) for a node
            value = not is_bad if role == POWERED else True
            if is_bad:
                word = "on" if role == POWERED else "running"
                assumed.append(f"{'' if value else '~'}{word}({name})")
        init.update(PddlAtom(p, (o,)) for p, o in words.facts(role, name, value))
    pred, holds = words.goal()
    goal = tuple(PddlAtom(pred, (name,)) for name in model.types)
    if ignored:
        log.debug("observations not in the repair domain, ignored: %s", ignored)
    return RepairProblem(model, bad_set, frozenset(init), goal, tuple(assumed), tuple(ignored),
                         holds)


def split_atom(atom: str) -> tuple[str, tuple[str, ...]]:
    """``on(jaguar)`` -> ``("on", ("jaguar",))``."""
    if "(" not in atom:
        return atom, ()
    pred, rest = atom.split("(", 1)
    inner = rest.rstrip(")")
    return pred, tuple(a.strip() for a in inner.split(",") if a.strip())


def to_pddl(problem: RepairProblem, domain_name: str, name: str = "repair",
            types: Mapping[str, str] | None = None,
            predicates: Collection[str] | None = None) -> str:
    """The problem as a PDDL file (objects by type, I, G). ``types``: each object's type in
    the domain (default: the model's); ``predicates``: the domain's (static facts of other
    predicates are left out)."""
    bad_names = [n for n in problem.model.types if not _PDDL_NAME.match(n)]
    if bad_names:
        raise ProblemError(
            f"component name(s) {', '.join(bad_names[:5])} are not valid PDDL names",
            "use letters, digits, '_' and '-', starting with a letter",
        )
    by_type: dict[str, list[str]] = {}
    for obj, typ in (problem.model.types if types is None else types).items():
        by_type.setdefault(typ, []).append(obj)
    lines = [f"(define (problem {name})", f"  (:domain {domain_name})", "  (:objects"]
    for typ, objs in by_type.items():
        lines.append(f"    {' '.join(objs)} - {typ}")
    lines.append("  )")
    lines.append("  (:init")
    statics = [a for a in problem.model.static_facts()
               if predicates is None or a.pred in predicates]
    facts = [*statics, *sorted(problem.init, key=str)]
    lines.extend(f"    ({a.pred} {' '.join(a.args)})" for a in facts)
    lines.append("  )")
    fmt = "({}{})" if problem.goal_holds else "(not ({}{}))"
    goals = " ".join(fmt.format(a.pred, "".join(" " + x for x in a.args)) for a in problem.goal)
    lines.append(f"  (:goal (and {goals})))")
    return "\n".join(lines) + "\n"
