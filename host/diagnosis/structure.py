"""Circuit structure read off a weak-fault-model theory, and the dominator reduction it allows.

A theory is *structured* when (checked here, else ``infer_structure`` returns None):

1. every clause holds exactly one health literal, and it is positive (``AB(c) or ...``: the
   weak fault model; clauses without one, i.e. global constraints, disqualify the theory);
2. each component ``c`` can be given *inputs* ``I(c)`` and *written* atoms ``W(c)`` (the
   other atoms of its clauses), the ``W`` sets pairwise disjoint, such that the graph
   ``c -> c'`` whenever ``W(c) ∩ I(c') ≠ ∅`` is acyclic;
3. *totality*: for every assignment of ``I(c)``, the healthy behaviour ``F_c`` (its clauses
   without ``AB(c)``) has a solution over ``W(c)`` (checked by truth table; components with
   more than ``MAX_ATOMS`` atoms disqualify the theory).

How ``W(c)`` is picked (the atom named like the component if it is a total function of the
others, else the atoms no other component mentions if they are, else such a function atom,
the first atom of the first clause on ties; plus the atoms no other component mentions) is a
heuristic; soundness rests only on 1-3, which are verified.

**Dominance (exact for minimal cardinality).** Let the *observation points* be the components
that write an observed atom, and say ``h`` dominates ``g`` when every path from ``g`` to an
observation point passes through ``h``. If ``D`` is a diagnosis and ``g ∈ D`` is dominated by
``h``, then ``D' = D - {g} + {h}`` is a diagnosis: take a model of ``D``, make ``g`` healthy
and recompute, in topological order, the written atoms of every healthy component reachable
from ``g`` without passing through ``h`` (possible by totality). Only those atoms change; none
is observed (else that path would reach an observation point avoiding ``h``), ``h`` is now
abnormal and so unconstrained, and every other clause is untouched. Hence every minimal-
cardinality diagnosis maps onto one made of *top-level* components only (those whose immediate
post-dominator is the virtual sink after all observation points), of the same size (two gates
mapping to the same top-level one would give a smaller diagnosis): the minimum cardinality can
be searched over the top-level components alone, and a minimal-cardinality diagnosis found
there is one of the full problem. Components from which no observation point is reachable are
in no subset-minimal diagnosis at all (same argument, with no ``h``). This is the cone
abstraction of Siddiqi & Huang ("Hierarchical diagnosis of multiple faults", IJCAI 2007) and
Metodi et al. (JAIR 2014).
"""

from __future__ import annotations

import itertools
from collections.abc import Iterable
from dataclasses import dataclass, field

from host.diagnosis.logic import Theory, ab_component

MAX_ATOMS = 14  # per component, for the truth-table totality check


@dataclass
class Structure:
    """``order``: component indexes, topological (writers before readers);
    ``written[c]``/``readers[c]``: the atoms ``c`` writes, the components reading them."""

    order: list[int]
    written: list[frozenset[str]]
    readers: list[list[int]]
    _top_cache: dict[frozenset[str], dict[int, list[int]]] = field(default_factory=dict)
    _written_any: frozenset[str] | None = None

    def top_level(self, observed: Iterable[str]) -> frozenset[int]:
        """Components not dominated by another one w.r.t. the observed atoms (see module
        doc); components that reach no observed atom are left out."""
        return frozenset(self.regions(observed))

    def regions(self, observed: Iterable[str]) -> dict[int, list[int]]:
        """Each top-level component with the components it stands for: itself and those
        whose nearest top-level dominator it is (topological order). Every minimal-
        cardinality diagnosis takes exactly one component from each region of a top-level
        minimal-cardinality diagnosis (module doc)."""
        key = frozenset(observed)
        cached = self._top_cache.get(key)
        if cached is not None:
            return cached
        pos = {c: i for i, c in enumerate(self.order)}
        sink = -1
        dead = -2
        ipdom: dict[int, int] = {}
        for c in reversed(self.order):
            if self.written[c] & key:
                ipdom[c] = sink
                continue
            succ = [s for s in self.readers[c] if ipdom[s] != dead]
            if not succ:
                ipdom[c] = dead
                continue
            cur = succ[0]
            for s in succ[1:]:
                a, b = cur, s
                while a != b:
                    if a == sink or b == sink:
                        a = b = sink
                        break
                    if pos[a] < pos[b]:
                        a = ipdom[a]
                    else:
                        b = ipdom[b]
                cur = a
            ipdom[c] = cur
        owner: dict[int, int] = {}
        for c in reversed(self.order):  # a dominator comes after what it dominates
            d = ipdom[c]
            if d == sink:
                owner[c] = c
            elif d != dead:
                owner[c] = owner[d]
        regions: dict[int, list[int]] = {c: [] for c in self.order if ipdom[c] == sink}
        for c in self.order:
            if c in owner:
                regions[owner[c]].append(c)
        if len(self._top_cache) > 16:
            self._top_cache.clear()
        self._top_cache[key] = regions
        return regions

    def reach(self, atoms: Iterable[str]) -> list[int]:
        """Per component, how many of ``atoms`` it can influence (it writes them, or a
        component it feeds, transitively, does)."""
        bit = {a: 1 << i for i, a in enumerate(dict.fromkeys(atoms))}
        mask = [0] * len(self.order)
        for c in reversed(self.order):
            m = 0
            for a in self.written[c]:
                m |= bit.get(a, 0)
            for r in self.readers[c]:
                m |= mask[r]
            mask[c] = m
        return [m.bit_count() for m in mask]

    def writes(self, atom: str) -> bool:
        """Does some component write ``atom`` (else it is an input of the circuit)?"""
        if self._written_any is None:
            self._written_any = frozenset().union(*self.written)
        return atom in self._written_any


def _total(clauses: list[list[tuple[str, bool]]], inputs: list[str], written: list[str]) -> bool:
    """For every assignment of ``inputs`` some assignment of ``written`` satisfies all."""
    for ins in itertools.product((False, True), repeat=len(inputs)):
        fixed = dict(zip(inputs, ins, strict=True))
        # clauses already satisfied by the inputs drop out; the rest must be satisfiable
        rest = [cl for cl in clauses if not any(fixed.get(a) is v for a, v in cl)]
        rest_w = [[(a, v) for a, v in cl if a not in fixed] for cl in rest]
        if any(not cl for cl in rest_w):
            return False
        for outs in itertools.product((False, True), repeat=len(written)):
            world = dict(zip(written, outs, strict=True))
            if all(any(world[a] is v for a, v in cl) for cl in rest_w):
                break
        else:
            return False
    return True


def infer_structure(theory: Theory) -> Structure | None:
    comps = theory.components
    index = {c: i for i, c in enumerate(comps)}
    bodies: list[list[list[tuple[str, bool]]]] = [[] for _ in comps]
    for clause in theory.clauses:
        owners = [lit for lit in clause.lits if ab_component(lit.atom) is not None]
        if len(owners) != 1 or not owners[0].positive:
            return None
        owner = index.get(ab_component(owners[0].atom) or "")
        if owner is None:
            return None
        bodies[owner].append([(lit.atom, lit.positive) for lit in clause.lits
                              if lit is not owners[0]])
    mentioned_by: dict[str, set[int]] = {}
    atoms_of: list[list[str]] = []
    for i, body in enumerate(bodies):
        atoms = list(dict.fromkeys(a for cl in body for a, _ in cl))
        if len(atoms) > MAX_ATOMS:
            return None
        atoms_of.append(atoms)
        for a in atoms:
            mentioned_by.setdefault(a, set()).add(i)
    # candidate outputs: atoms shared with other components that are total functions of the
    # other shared atoms; unambiguous components claim theirs first
    cands: list[list[str]] = []
    owns: list[list[str]] = []
    memo: dict[tuple[object, ...], bool] = {}

    def total(i: int, inputs: list[str], written: list[str]) -> bool:
        # gates of one type and fan-in share the answer: key on the renamed clauses
        ren = {a: k for k, a in enumerate([*inputs, *written])}
        key = (len(inputs), len(written),
               tuple(sorted(tuple(sorted((ren[a], v) for a, v in cl)) for cl in bodies[i])))
        r = memo.get(key)
        if r is None:
            r = memo[key] = _total(bodies[i], inputs, written)
        return r

    for i, atoms in enumerate(atoms_of):
        own = [a for a in atoms if mentioned_by[a] == {i}]
        ports = [a for a in atoms if a not in own]
        owns.append(own)
        named = comps[i] in ports and total(
            i, [a for a in ports if a != comps[i]], [comps[i], *own])
        if named:  # the atom named like the component is a total function of the rest
            cands.append([comps[i]])
        elif own and total(i, ports, own):  # writes only what no one else reads
            cands.append([])
        else:
            cands.append([x for x in ports
                          if total(i, [a for a in ports if a != x], [x, *own])])
            if not cands[i] and not total(i, ports, own):
                return None
    claimed = {c[0] for c in cands if len(c) == 1}
    written: list[frozenset[str]] = []
    for i, cs in enumerate(cands):
        if len(cs) > 1:
            first = bodies[i][0][0][0] if bodies[i] and bodies[i][0] else None
            free = [x for x in cs if x not in claimed] or cs
            pick = next((x for x in free if x == first), None) or free[0]
            claimed.add(pick)
            cs = [pick]
        written.append(frozenset([*cs, *owns[i]]))
    writer: dict[str, int] = {}
    for i, w in enumerate(written):
        for a in w:
            if a in writer:
                return None
            writer[a] = i
    readers: list[list[int]] = [[] for _ in comps]
    indeg = [0] * len(comps)
    for i, atoms in enumerate(atoms_of):
        preds = {writer[a] for a in atoms if a not in written[i] and a in writer}
        for p in preds:
            readers[p].append(i)
            indeg[i] += 1
    order = [i for i in range(len(comps)) if indeg[i] == 0]
    k = 0
    while k < len(order):
        for s in readers[order[k]]:
            indeg[s] -= 1
            if indeg[s] == 0:
                order.append(s)
        k += 1
    if len(order) != len(comps):
        return None  # cyclic
    return Structure(order, written, readers)
