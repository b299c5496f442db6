"""Clauses generated from a robot's structure: ``SystemModel`` -> ``Theory``.

Paper 000 §IV-D's clauses 1-6, generalised where the paper is silent, plus the board's:

1. switchable hardware ``h``:        ``~AB(h) -> on(h)``
2. driver ``s`` (SN), ``t`` in out(s): ``~AB(s), ~AB(h) for h in hardware(s), ok(i) for i in
   in(t, s) -> ok(t)`` (the paper has no inputs here; an output listing none is the paper's)
3. hardware node ``n`` (HN):          the same with its (non-switchable) hardware
4. ordinary node ``n`` (N):           ``~AB(n), ok(i) for i in in(t, n) -> ok(t)``
5. every node ``n``:                  ``~AB(n) -> running(n)``
6. related values ``v1, v2`` on topics of nodes ``n1, n2``: ``~AB(n1), ~AB(n2) -> matched(v1,v2)``
7. board, current band:               ``~AB(h), on(h) -> in_band(h)``  (a healthy powered device
                                      draws current in its band; only for devices with a band)
8. board, protection:                 ``~AB(h) -> ~tripped(h)`` (a tripped or latched channel is
                                      not a healthy one)
9. trends, for each value ``v``:      at most one of ``inc(v)``, ``dec(v)``, ``const(v)``

Each clause carries its rule number and name as ``origin``; ``dxboard model clauses`` prints them.
"""

from __future__ import annotations

from itertools import combinations

import host.atoms as A
from host.diagnosis.logic import Clause, Literal, Theory, horn, nab
from host.diagnosis.model import ComponentKind, SystemModel

ORIGINS = {
    1: "1 switchable hardware must be powered",
    2: "2 driver of switchable hardware",
    3: "3 hardware node",
    4: "4 ordinary node",
    5: "5 healthy nodes run",
    6: "6 related values match",
    7: "7 board: current in band",
    8: "8 board: tripped channel",
    9: "9 one trend per value",
    10: "10 a healthy board is heard by the host",
}


def _pos(atom: A.Atom | str) -> Literal:
    return Literal(str(atom), True)


def generate(model: SystemModel) -> Theory:
    """The system description of ``model`` (components in the file's order)."""
    out: list[Clause] = []
    for h in model.by_kind(ComponentKind.SH):
        out.append(horn([nab(h.name)], [_pos(A.on(h.name))], ORIGINS[1]))
    for rule, kind in ((2, ComponentKind.SN), (3, ComponentKind.HN), (4, ComponentKind.N)):
        for n in model.by_kind(kind):
            hw = [] if kind is ComponentKind.N else [nab(h) for h in n.hardware]
            for topic, inputs in n.publishes.items():
                body = [nab(n.name), *hw, *(_pos(A.ok(i)) for i in inputs)]
                out.append(horn(body, [_pos(A.ok(topic))], ORIGINS[rule]))
    for n in model.by_kind(ComponentKind.N, ComponentKind.HN, ComponentKind.SN):
        out.append(horn([nab(n.name)], [_pos(A.running(n.name))], ORIGINS[5]))
    out.extend(_related(model))
    for h in model.by_kind(ComponentKind.SH):
        if h.current is not None:
            body = [nab(h.name), _pos(A.on(h.name))]
            out.append(horn(body, [_pos(A.in_band(h.name))], ORIGINS[7]))
    for h in model.by_kind(ComponentKind.SH):
        out.append(horn([nab(h.name), _pos(A.tripped(h.name))], [], ORIGINS[8]))
    values = dict.fromkeys(v for vs in model.values.values() for v in vs)
    for v in values:
        for a, b in combinations(A.TRENDS, 2):
            out.append(horn([_pos(A.trend(a, v)), _pos(A.trend(b, v))], [], ORIGINS[9]))
    if model.board is not None:
        out.append(horn([nab(model.board)], [_pos(A.link(model.board))], ORIGINS[10]))
    priors = {c.name: c.prior for c in model.components.values() if c.prior is not None}
    return Theory(tuple(model.components), tuple(out), priors)


def _related(model: SystemModel) -> list[Clause]:
    out: list[Clause] = []
    seen: set[tuple[str, str, str, str]] = set()
    for v1, v2 in model.related:
        for t1, vs1 in model.values.items():
            for t2, vs2 in model.values.items():
                if v1 not in vs1 or v2 not in vs2:
                    continue
                for n1 in model.publishers(t1):
                    for n2 in model.publishers(t2):
                        key = (n1.name, n2.name, v1, v2)
                        if key in seen or not (n1.is_node and n2.is_node):
                            continue
                        seen.add(key)
                        body = list(dict.fromkeys([nab(n1.name), nab(n2.name)]))
                        out.append(horn(body, [_pos(A.matched(v1, v2))], ORIGINS[6]))
    return out
