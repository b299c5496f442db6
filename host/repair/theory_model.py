"""A ``RepairModel`` read off a theory's clauses: planning for a tug model file.

A ``system.yaml`` says what each component is; a tug model (the original system's format,
paper 000 §IV-D) says it only through its clauses. They follow the paper's rules, so the kinds
and dependencies can be read back:

- a component ``c`` with an atom ``on(c)`` is switchable hardware (clause 1,
  ``~AB(h) -> on(h)``); one with ``running(c)`` is a node (clause 5);
- a component that, healthy, produces a topic (``~AB(n), ... -> ok(t)``: clauses 2-4) is a
  node too, and a driver when the same rule needs a switchable device (clause 2,
  ``~AB(s), ~AB(h) -> ok(t)``);
- a node needs the other components its output rules need healthy, and the producers of the
  topics they need ``ok`` (clause 4, ``~AB(n), ok(i) -> ok(t)``);
- anything else is other hardware (no action of a repair domain switches it).

Dependencies inside a cycle are dropped as for ``system.yaml`` (``problem.repair_model``).
Nothing is protected: a tug model has no board section.
"""

from __future__ import annotations

from host.diagnosis.logic import Theory, ab_component
from host.repair.problem import (
    DRIVER,
    HARDWARE,
    NODE,
    SWITCHABLE,
    RepairModel,
    drop_cycles,
    split_atom,
)


def repair_model_of(theory: Theory, name: str) -> RepairModel:
    """The planner's view of ``theory`` (see the module docstring)."""
    comps = set(theory.components)
    atoms = theory.atoms()
    switchable = {c for c in comps if f"on({c})" in atoms}
    running = {c for c in comps if f"running({c})" in atoms}
    # (components a rule needs healthy, the ok inputs it needs, its ok head)
    rules: list[tuple[set[str], set[str], str]] = []
    for clause in theory.clauses:
        heads = [x.atom for x in clause.lits if x.positive and ab_component(x.atom) is None]
        healthy = {c for x in clause.lits if x.positive
                   if (c := ab_component(x.atom)) is not None}
        inputs = {x.atom for x in clause.lits if not x.positive and split_atom(x.atom)[0] == "ok"}
        if len(heads) == 1 and healthy and split_atom(heads[0])[0] == "ok":
            rules.append((healthy, inputs, heads[0]))
    nodes = running - switchable
    drivers: set[str] = set()
    for healthy, _, _ in rules:
        candidates = healthy - switchable
        named = candidates & running  # the node of the rule, where running() says which
        found = named or candidates
        nodes |= found
        if healthy & switchable:
            drivers |= found
    producers: dict[str, set[str]] = {}  # topic atom -> the nodes that produce it
    for healthy, _, head in rules:
        producers.setdefault(head, set()).update(healthy & nodes)
    needs: dict[str, tuple[str, ...]] = {}
    for n in sorted(nodes):
        deps: dict[str, None] = {}
        for healthy, inputs, _ in rules:
            if n in healthy:
                deps.update(dict.fromkeys(sorted(healthy - {n})))
                for i in sorted(inputs):
                    deps.update(dict.fromkeys(sorted(producers.get(i, set()) - {n})))
        needs[n] = tuple(deps)
    types: dict[str, str] = {}
    for c in theory.components:
        if c in switchable:
            types[c] = SWITCHABLE
        elif c in nodes:
            types[c] = DRIVER if c in drivers else NODE
        else:
            types[c] = HARDWARE
    return RepairModel(name, types, drop_cycles(needs))
