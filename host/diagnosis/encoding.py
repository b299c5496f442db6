"""A theory compiled for the SAT engine: its variable numbers, its clauses as integers, and its
circuit structure; what ``SatContext`` builds from a ``Theory`` before any search.

``encode(theory)`` numbers the atoms (the health atoms ``AB(c)`` first, ``1..n`` in the order
of ``theory.components``, then every other atom in the order the clauses first mention it),
writes each clause as a list of signed numbers, and infers the circuit structure
(``structure.infer_structure``) on first use, or at once with ``structure=True``. The result
depends on the theory alone, so it can be kept beside the parsed model (``cache.py`` stores
both: ``dxboard diagnose`` then skips this step, as Python skips compiling a module whose
``.pyc`` is current; on c7552 it is about 100 ms of CPU a run, the structure most of it).

An ``Encoding`` is shared, never changed by its users: ``SatContext`` copies the variable map
before it adds variables of its own, and the solver and PySAT's formulas copy the clauses.
"""

from __future__ import annotations

from dataclasses import dataclass, field

from host.diagnosis.logic import Theory, ab
from host.diagnosis.structure import Structure, infer_structure


@dataclass
class Encoding:
    """``vars``: atom -> variable number (``AB(c)`` of the i-th component is ``i + 1``);
    ``clauses``: the theory's clauses in those numbers, in the theory's order."""

    theory: Theory
    vars: dict[str, int]
    clauses: list[list[int]]
    _structure: Structure | bool | None = field(default=False, repr=False,
                                                compare=False)  # False: not inferred yet

    def structure(self) -> Structure | None:
        """The theory's circuit structure (None: it has none), inferred once."""
        if self._structure is False:
            self._structure = infer_structure(self.theory)
        assert not isinstance(self._structure, bool)
        return self._structure


def encode(theory: Theory, structure: bool = False) -> Encoding:
    """The encoding of ``theory`` (module docstring); ``structure``: infer it now."""
    numbers: dict[str, int] = {}
    for c in theory.components:
        numbers.setdefault(ab(c), len(numbers) + 1)
    clauses: list[list[int]] = []
    for clause in theory.clauses:
        out = []
        for lit in clause.lits:
            v = numbers.get(lit.atom)
            if v is None:
                v = numbers[lit.atom] = len(numbers) + 1
            out.append(v if lit.positive else -v)
        clauses.append(out)
    enc = Encoding(theory, numbers, clauses)
    if structure:
        enc.structure()
    return enc
