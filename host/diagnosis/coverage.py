"""What the observations cover: a component whose observations expired is unknown, not healthy.

Consistency-based diagnosis explains the observations it is given; with none about a component
it finds nothing wrong with it, and "nothing wrong" would read as "all healthy" although
nobody looked. ``Coverage(theory)`` knows, for each component, the observable atoms that share
a clause with its ``AB`` atom (what can speak about it: its output topics, its process, its
current). ``unknown(seen, known)`` names the components with at least one such atom that was
observed once in this run (``seen``) and has no value now (``known`` lacks it: it expired, or
its observer reported unknown): what they covered is unknown until they come back. Atoms no
observer ever reported do not count, so a model richer than its observers stays quiet.
``observe(known)`` keeps ``seen`` for a diagnosis loop (the daemon's and the bag replay's).
"""

from __future__ import annotations

from collections.abc import Set

from host.diagnosis.logic import Theory, ab_component


class Coverage:
    """Component -> the observable atoms that bear on it directly (one clause away)."""

    def __init__(self, theory: Theory) -> None:
        observable = theory.observable_atoms()
        cover: dict[str, set[str]] = {c: set() for c in theory.components}
        for clause in theory.clauses:
            atoms = {lit.atom for lit in clause.lits}
            for atom in atoms:
                component = ab_component(atom)
                if component is not None and component in cover:
                    cover[component] |= atoms & observable
        self.cover = {c: frozenset(a) for c, a in cover.items()}
        self.seen: set[str] = set()  # atoms observed at least once (``observe``)

    def unknown(self, seen: Set[str], known: Set[str]) -> tuple[str, ...]:
        """The components (in the model's order) an observation seen before but unknown now
        bears on."""
        lost = seen - known
        if not lost:
            return ()
        return tuple(c for c, atoms in self.cover.items() if atoms & lost)

    def observe(self, known: Set[str]) -> tuple[str, ...]:
        """``unknown`` of a run: ``known`` (the atoms with a value now) joins what was seen."""
        self.seen |= known
        return self.unknown(self.seen, known)
