"""The healthy value of each observable atom: what it is when no component is abnormal.

A person reading ``tripped(hokuyo) = false`` next to ``on(hokuyo) = false`` needs to know that
the first is as it should be and the second is not. Which value is healthy is a question to the
model, not to the atom's name: ``healthy_values(theory)`` asks the SAT solver, with every
``~AB(c)`` assumed, whether the theory entails the atom (then ``True`` is healthy) or its
negation (``False``); an atom the healthy theory leaves free (a trend, ``inc(v)``) gets no
entry, and neither does any atom of a theory that contradicts itself when all is healthy. Two
solver calls per atom on one incremental solver (``SatContext``); the daemon asks once at
start, and the page colours observations by it.
"""

from __future__ import annotations

import logging
from collections.abc import Iterable

from host.diagnosis.logic import Theory
from host.diagnosis.satctx import SatContext

log = logging.getLogger(__name__)


def healthy_values(theory: Theory, atoms: Iterable[str] | None = None) -> dict[str, bool]:
    """``{atom: value}`` for the atoms (default: the theory's observable ones) whose value
    the theory entails when every component is healthy."""
    wanted = sorted(theory.observable_atoms() if atoms is None else set(atoms))
    known = theory.atoms()
    ctx = SatContext(theory)
    try:
        healthy = [-v for v in ctx.ab_vars]
        if not ctx.solve(healthy):
            log.warning("the model contradicts itself with every component healthy; "
                        "no observation has a healthy value")
            return {}
        out: dict[str, bool] = {}
        for atom in wanted:
            if atom not in known:  # no clause mentions it: free
                continue
            v = ctx.var(atom)
            can_be_true = ctx.solve([*healthy, v])
            can_be_false = ctx.solve([*healthy, -v])
            if can_be_true != can_be_false:
                out[atom] = bool(can_be_true)
        return out
    finally:
        ctx.close()
