"""The grounded planning task: fluent atoms numbered, operators as bit masks.

What the grounder hands the search (pyperplan's ``Task``, made fast for thousands of
components). A ground *atom* is ``(pred, args)`` and gets a number ``a``; a *literal* is the
integer ``2*a + 1`` (the atom is true) or ``2*a`` (false), so ``lit ^ 1`` negates it. A *state*
is a Python ``int`` whose bit ``a`` is set when atom ``a`` is true (closed world). A ``GroundOp``
keeps its precondition and effects twice: as literal tuples (for relevance analysis, stubborn
sets and deordering) and as masks (for applying it in a few integer operations). Conditional
effects (``when``) are ``CondEffect`` values evaluated in the state the operator is applied in.
Static predicates are gone by now: the grounder evaluated them.
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from dataclasses import dataclass, field


def lit(atom: int, positive: bool) -> int:
    return 2 * atom + (1 if positive else 0)


def lit_atom(literal: int) -> int:
    return literal >> 1


def lit_positive(literal: int) -> bool:
    return bool(literal & 1)


def holds(literal: int, state: int) -> bool:
    return bool((state >> (literal >> 1)) & 1) == bool(literal & 1)


def masks(literals: Iterable[int]) -> tuple[int, int]:
    """(mask of atoms that must be true, mask of atoms that must be false)."""
    t = f = 0
    for x in literals:
        if x & 1:
            t |= 1 << (x >> 1)
        else:
            f |= 1 << (x >> 1)
    return t, f


@dataclass(frozen=True, slots=True)
class CondEffect:
    """``when cond then eff``: ``cond`` and ``eff`` are literal tuples."""

    cond: tuple[int, ...]
    eff: tuple[int, ...]
    cond_t: int
    cond_f: int
    add: int
    delete: int

    @staticmethod
    def make(cond: Sequence[int], eff: Sequence[int]) -> CondEffect:
        ct, cf = masks(cond)
        add, dele = masks(eff)
        return CondEffect(tuple(cond), tuple(eff), ct, cf, add, dele)


@dataclass(frozen=True, slots=True)
class GroundOp:
    """One ground action: ``name(args)`` with literal tuples and masks."""

    name: str
    args: tuple[str, ...]
    pre: tuple[int, ...]
    eff: tuple[int, ...]
    cond: tuple[CondEffect, ...]
    cost: float
    pre_t: int
    pre_f: int
    add: int
    delete: int

    @staticmethod
    def make(
        name: str,
        args: tuple[str, ...],
        pre: Sequence[int],
        eff: Sequence[int],
        cond: Sequence[CondEffect] = (),
        cost: float = 1.0,
    ) -> GroundOp:
        pt, pf = masks(pre)
        add, dele = masks(eff)
        return GroundOp(name, args, tuple(pre), tuple(eff), tuple(cond), cost, pt, pf, add, dele)

    def applicable(self, state: int) -> bool:
        return (state & self.pre_t) == self.pre_t and not (state & self.pre_f)

    def apply(self, state: int) -> int:
        add, dele = self.add, self.delete
        for c in self.cond:
            if (state & c.cond_t) == c.cond_t and not (state & c.cond_f):
                add |= c.add
                dele |= c.delete
        return (state & ~dele) | add

    def effect_literals(self) -> tuple[int, ...]:
        """Every literal the operator may make true (conditional ones included)."""
        if not self.cond:
            return self.eff
        return self.eff + tuple(x for c in self.cond for x in c.eff)

    def read_atoms(self) -> set[int]:
        out = {x >> 1 for x in self.pre}
        for c in self.cond:
            out.update(x >> 1 for x in c.cond)
        return out

    def write_atoms(self) -> set[int]:
        return {x >> 1 for x in self.effect_literals()}

    def label(self) -> str:
        return f"{self.name}({', '.join(self.args)})"


# a planning task in Fast Downward's sense (domain + objects, grounded); emulator/parts/sched.py
# has asyncio's Task, which it must be named as (scripts/names.py)
@dataclass
class Task:
    """Fluent atoms, their numbers, and the ground operators of one domain + object set.

    A task depends only on the domain, the objects and the static facts, never on a
    diagnosis: the planner grounds once per robot model and reuses the task for every repair.
    ``removed`` lists operators the problem layer forbade (protected components) with why.
    """

    atoms: list[tuple[str, tuple[str, ...]]]
    index: dict[tuple[str, tuple[str, ...]], int]
    ops: list[GroundOp]
    removed: list[tuple[str, str]] = field(default_factory=list)
    _achievers: dict[int, list[int]] | None = None

    def atom_id(self, pred: str, args: tuple[str, ...]) -> int:
        key = (pred, args)
        a = self.index.get(key)
        if a is None:
            a = self.index[key] = len(self.atoms)
            self.atoms.append(key)
        return a

    def literal(self, pred: str, args: tuple[str, ...], positive: bool = True) -> int:
        return lit(self.atom_id(pred, args), positive)

    def describe(self, literal: int) -> str:
        pred, args = self.atoms[literal >> 1]
        text = f"{pred}({','.join(args)})"
        return text if literal & 1 else "~" + text

    def state(self, true_atoms: Iterable[tuple[str, tuple[str, ...]]]) -> int:
        s = 0
        for pred, args in true_atoms:
            s |= 1 << self.atom_id(pred, args)
        return s

    def achievers(self) -> dict[int, list[int]]:
        """literal -> indices of the operators that may make it true (built once)."""
        if self._achievers is None:
            out: dict[int, list[int]] = {}
            for i, op in enumerate(self.ops):
                for x in op.effect_literals():
                    out.setdefault(x, []).append(i)
            self._achievers = out
        return self._achievers
