"""The mission layer's context: the knowledge base (paper 001 §II-A), atoms in PDDL's words.

The KB is a set of ground atoms (``(at office)``) and the objects they speak of (objects the
robot learns about — a victim it found — are added as they come). Only three things change it,
each emitted as a ``KbChange`` on the daemon's stream so that the journal can replay the KB
at every step: an action's start or end effects (``source="effect"``), an observation that
overrides what the KB believed (``"sensing"``; the concept of sensing actions), and its first
filling (``"init"``). ``check`` evaluates an action's conditions against the KB and returns
one ``ConditionCheck`` per literal, so that a dispatch records what was checked and how it came
out.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable

from host.events import ConditionCheck, Event, KbChange
from host.planning.temporal_pddl import Atom, Literal, spell


class KnowledgeBase:
    def __init__(self, objects: dict[str, str], emit: Callable[[Event], None]) -> None:
        self.atoms: set[Atom] = set()
        self.objects = dict(objects)
        self.emit = emit

    def holds(self, lits: Iterable[Literal]) -> bool:
        return all((atom in self.atoms) == pos for atom, pos in lits)

    def check(self, lits: Iterable[Literal], when: str) -> list[ConditionCheck]:
        return [ConditionCheck(spell(a), when, pos, (a in self.atoms) == pos) for a, pos in lits]

    def snapshot(self) -> tuple[str, ...]:
        return tuple(sorted(spell(a) for a in self.atoms))

    def state(self) -> frozenset[Atom]:
        return frozenset(self.atoms)

    def change(self, lits: Iterable[Literal], source: str, cause: str = "",
               dispatch_id: str = "") -> KbChange | None:
        """Make ``lits`` true in the KB; emits and returns the change (None: none)."""
        added, removed = [], []
        for atom, pos in lits:
            if pos and atom not in self.atoms:
                self.atoms.add(atom)
                added.append(spell(atom))
            elif not pos and atom in self.atoms:
                self.atoms.discard(atom)
                removed.append(spell(atom))
        if not added and not removed:
            return None
        change = KbChange(tuple(added), tuple(removed), source, cause, dispatch_id)
        self.emit(change)
        return change

    def learn(self, obj: str, typ: str) -> None:
        """An object the robot found (a victim) joins the ones the planner may use."""
        self.objects.setdefault(obj, typ)
