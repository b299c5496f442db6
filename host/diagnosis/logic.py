"""Propositional literals, clauses and theories: the language the diagnoser speaks.

An *atom* is a ground proposition written ``pred(arg, ...)`` (``on(jaguar)``, ``ok(/scan)``,
``matched(v1,v2)``); whitespace is not significant and is removed. A ``Literal`` is an atom
with a sign. A ``Clause`` is a disjunction of literals (general clauses, not only Horn) with
an ``origin`` naming the rule that produced it. A ``Theory`` is a system description in
Reiter's sense: the diagnosable components (each with the health atom ``AB(c)``), the clauses
and the prior fault probability of each component. Theories are plain immutable values: the
``system.yaml`` generator, the tug-format reader and the ISCAS benchmark all produce one, and
any ``Diagnoser`` can be built from any of them.
"""

from __future__ import annotations

import re
from collections.abc import Iterable, Mapping
from dataclasses import dataclass, field

AB_PREDICATE = "AB"
DEFAULT_PRIOR = 0.01
_ATOM = re.compile(r"^[A-Za-z_][\w.\-]*(\([^()]*\))?$")
_NEGATIONS = ("~", "¬", "!", "-")
_NOT = re.compile(r"not\s")
_SPACE = re.compile(r"\s+")


def ab(component: str) -> str:
    """The health atom of a component: ``AB(c)`` is true when ``c`` is abnormal."""
    return f"{AB_PREDICATE}({component})"


def ab_component(atom: str) -> str | None:
    """The component named by a health atom ``AB(c)``, else None."""
    if atom.startswith(AB_PREDICATE + "(") and atom.endswith(")"):
        return atom[len(AB_PREDICATE) + 1 : -1]
    return None


def normalize_atom(text: str) -> str:
    """``ok ( /scan )`` -> ``ok(/scan)``; raise ValueError if it is not an atom."""
    atom = _SPACE.sub("", text)
    if not atom or not _ATOM.match(atom):
        raise ValueError(f"{text.strip()!r} is not an atom like ok(/scan) or on(jaguar)")
    return atom


@dataclass(frozen=True, order=True)
class Literal:
    """An atom or its negation."""

    atom: str
    positive: bool = True

    def __neg__(self) -> Literal:
        return Literal(self.atom, not self.positive)

    def __str__(self) -> str:
        return self.atom if self.positive else "~" + self.atom


def parse_literal(text: str, neg_prefixes: Iterable[str] = ()) -> Literal:
    """Parse ``ok(/scan)``, ``~on(jaguar)``, ``not on(jaguar)``, ``¬on(x)`` or ``!on(x)``.

    ``neg_prefixes`` adds prefixes that also mean negation (the tug format's ``neg_prefix``).
    Raises ValueError with the reason.
    """
    s = text.strip()
    positive = True
    while True:
        if s.startswith(_NEGATIONS):
            s, positive = s[1:].strip(), not positive
        elif _NOT.match(s):
            s, positive = s[3:].strip(), not positive
        else:
            for prefix in neg_prefixes:
                if prefix and s.startswith(prefix) and len(s) > len(prefix):
                    s, positive = s[len(prefix) :].strip(), not positive
                    break
            else:
                break
    return Literal(normalize_atom(s), positive)


@dataclass(frozen=True)
class Clause:
    """A disjunction of literals; ``origin`` says which rule generated it."""

    lits: tuple[Literal, ...]
    origin: str = ""

    def body_head(self) -> tuple[list[str], list[str]]:
        """The clause as a rule ``body -> head``: negative literals and positive ``AB`` atoms
        become conditions (``~AB(c)`` for the latter), other positive literals the head."""
        body: list[str] = []
        head: list[str] = []
        for lit in self.lits:
            if not lit.positive:
                body.append(lit.atom)
            elif ab_component(lit.atom) is not None:
                body.append("~" + lit.atom)
            else:
                head.append(lit.atom)
        return body, head

    def __str__(self) -> str:
        body, head = self.body_head()
        rhs = " | ".join(head) if head else "false"
        return f"{', '.join(body)} -> {rhs}" if body else rhs


@dataclass(frozen=True)
class Theory:
    """A system description: components, clauses over atoms, and priors.

    ``components`` are the diagnosable ones (``AB(c)`` for each); ``priors`` maps a component
    to its prior fault probability (``DEFAULT_PRIOR`` when absent). ``observables`` are the
    atoms observers may report; empty means "every non-``AB`` atom of the clauses".
    ``negations`` are the model's own prefixes that negate a literal (the tug format's
    ``neg_prefix``, e.g. ``not_``), accepted in observations beside ``~`` and ``not``;
    ``notes`` are what a person should know about how the model was read (said once).
    ``separate`` are atoms whose negation is an atom of its own, named ``separate_prefix`` +
    the atom (the original tug engine's reading of an atom ``props`` does not list: ``~a`` and
    ``not_a`` say ``not_a`` holds, nothing about ``a``).
    """

    components: tuple[str, ...]
    clauses: tuple[Clause, ...]
    priors: Mapping[str, float] = field(default_factory=dict)
    observables: frozenset[str] = frozenset()
    negations: tuple[str, ...] = ()
    notes: tuple[str, ...] = field(default=(), compare=False)
    separate: frozenset[str] = frozenset()
    separate_prefix: str = ""

    def atoms(self) -> set[str]:
        out = {ab(c) for c in self.components}
        for clause in self.clauses:
            out.update(lit.atom for lit in clause.lits)
        return out

    def observable_atoms(self) -> frozenset[str]:
        if self.observables:
            return self.observables
        return frozenset(a for a in self.atoms() if ab_component(a) is None)

    def prior(self, component: str) -> float:
        return float(self.priors.get(component, DEFAULT_PRIOR))

    def parse(self, text: str) -> Literal:
        """A literal in this model's language (its own negation prefixes included)."""
        lit = parse_literal(text, self.negations)
        if not lit.positive and lit.atom in self.separate:
            return Literal(self.separate_prefix + lit.atom, True)
        return lit


def horn(body: Iterable[Literal], head: Iterable[Literal], origin: str = "") -> Clause:
    """The clause of ``b1 ∧ … ∧ bn -> h1 or … or hm`` (``~AB(c)`` in a body is a literal too)."""
    return Clause(tuple([-b for b in body] + list(head)), origin)


def nab(component: str) -> Literal:
    """The literal ``~AB(c)`` (component c is healthy)."""
    return Literal(ab(component), False)


def format_clauses(theory: Theory) -> str:
    """Readable listing, one rule a line, grouped by origin."""
    lines: list[str] = []
    last = None
    for clause in theory.clauses:
        if clause.origin != last:
            lines.append(f"# {clause.origin or 'clauses'}")
            last = clause.origin
        lines.append(str(clause))
    return "\n".join(lines) + "\n"
