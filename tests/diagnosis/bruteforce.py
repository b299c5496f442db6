"""Brute-force reference diagnoses and random small theories, for cross-checking the engines."""

from __future__ import annotations

import itertools
import random

from host.diagnosis import Clause, Literal, Theory, ab


def random_theory(rng: random.Random) -> tuple[Theory, list[Literal]]:
    """A random general clause set over up to 6 components and 5 other atoms, and random
    observations over the other atoms."""
    n = rng.randint(1, 6)
    m = rng.randint(1, 5)
    comps = tuple(f"c{i}" for i in range(n))
    atoms = [f"x({j})" for j in range(m)]
    clauses = []
    for _ in range(rng.randint(1, 10)):
        size = rng.randint(1, 4)
        lits = []
        for _ in range(size):
            if rng.random() < 0.4:
                # mostly weak-fault style (~AB(c) in a body = AB(c) in the clause), sometimes not
                lits.append(Literal(ab(rng.choice(comps)), rng.random() < 0.85))
            else:
                lits.append(Literal(rng.choice(atoms), rng.random() < 0.5))
        clauses.append(Clause(tuple(lits)))
    mentioned = sorted(
        {lit.atom for c in clauses for lit in c.lits if not lit.atom.startswith("AB(")}
    )
    priors = {c: rng.choice([0.01, 0.05, 0.2]) for c in comps}
    theory = Theory(comps, tuple(clauses), priors)
    obs = [Literal(a, rng.random() < 0.5) for a in mentioned if rng.random() < 0.7]
    return theory, obs


def consistent(theory: Theory, obs: list[Literal], bad: frozenset[str]) -> bool:
    fixed = {ab(c): c in bad for c in theory.components}
    fixed.update({o.atom: o.positive for o in obs})
    free = sorted(theory.atoms() - set(fixed))
    for values in itertools.product([False, True], repeat=len(free)):
        world = {**fixed, **dict(zip(free, values, strict=True))}
        if all(any(world[lit.atom] == lit.positive for lit in cl.lits) for cl in theory.clauses):
            return True
    return False


def minimal_diagnoses(theory: Theory, obs: list[Literal]) -> list[frozenset[str]]:
    diagnoses = [
        frozenset(s)
        for k in range(len(theory.components) + 1)
        for s in itertools.combinations(theory.components, k)
        if consistent(theory, obs, frozenset(s))
    ]
    return [d for d in diagnoses if not any(e < d for e in diagnoses)]
