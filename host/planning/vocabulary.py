"""The repair domain's own words for health, power and running: declared, or inferred.

The planner builds I and G (paper 000 §IV-E) from a diagnosis and the observations, so it must
know which of the domain's predicates say that a component is abnormal or healthy, that a
device is powered and that a node runs. Domains differ: ours (``models/*/repair.pddl``) has
``ab``, ``on`` and ``running``, with the closed-world negation ``(not (on ?h))``; the original
TEDUSAR system's (paper 000's, ``repair_domain.pddl``) has ``bad`` and ``good`` as two separate
predicates and spells a false fact as a predicate of its own, ``not_on`` / ``not_running``,
with the prefix its model files call ``neg_prefix``.

A domain declares its words in a comment line (PDDL has no place for them)::

    ; dxboard-vocabulary: abnormal=bad healthy=good powered=on running=running negation=not_

Every key is optional. Without the line, or for the keys it leaves out, the words are
inferred from the original's conventions: abnormal is the first declared of ``ab``, ``bad``,
``abnormal``; healthy of ``nab``, ``good``, ``healthy``; powered ``on``; running ``running``;
and a predicate ``not_P`` (the ``negation`` prefix, ``not_`` unless declared) is the explicit
complement of ``P``. A domain with neither an abnormal nor a healthy word cannot express a
repair goal: the repair planner refuses it (``require_health``, naming the line to add),
though its own problem files still plan.

``Vocabulary`` turns a role and a value into the facts of I (``facts``) and the goal into
literals (``goal``); ``ROLE_OF_OBSERVATION`` maps the observers' literals (``on(d)``,
``running(n)``) to roles. The executor's expected effects can read ``powered`` / ``running``
from here (``RepairPlanner.vocabulary``).
"""

from __future__ import annotations

import re
from collections.abc import Mapping
from dataclasses import dataclass, field

from host.planning.errors import DomainError

ABNORMAL, HEALTHY, POWERED, RUNNING = "abnormal", "healthy", "powered", "running"
ROLES = (ABNORMAL, HEALTHY, POWERED, RUNNING)
DEFAULT_NEGATION = "not_"
INFERRED: Mapping[str, tuple[str, ...]] = {
    ABNORMAL: ("ab", "bad", "abnormal"),
    HEALTHY: ("nab", "good", "healthy"),
    POWERED: ("on",),
    RUNNING: ("running",),
}
#: the observers' literals (the diagnosis model's language) and the role each one fills
ROLE_OF_OBSERVATION: Mapping[str, str] = {"on": POWERED, "running": RUNNING}

NO_HEALTH = (
    "the domain has no predicate that says a component is abnormal or healthy, so no "
    "repair goal can be written in it",
    "add a comment line '; dxboard-vocabulary: abnormal=PRED' (or healthy=PRED) naming a "
    "one-argument predicate of the domain",
)

_DECLARATION = re.compile(r"^\s*;+\s*dxboard-vocabulary:(?P<body>.*)$", re.MULTILINE)


@dataclass(frozen=True)
class Vocabulary:
    """Which predicate fills each role (None: the domain has none), and the explicit
    complements (``on`` -> ``not_on``) the domain declares."""

    abnormal: str | None = "ab"
    healthy: str | None = None
    powered: str | None = "on"
    running: str | None = "running"
    complements: Mapping[str, str] = field(default_factory=dict)
    declared: tuple[str, ...] = ()  # the roles the domain file declared itself

    def role(self, name: str) -> str | None:
        return {ABNORMAL: self.abnormal, HEALTHY: self.healthy, POWERED: self.powered,
                RUNNING: self.running}[name]

    def facts(self, role: str, obj: str, value: bool) -> list[tuple[str, str]]:
        """The (predicate, object) facts of I that say ``role(obj)`` is ``value``: the role's
        predicate when true, its explicit complement (if any) when false; for health, the
        healthy predicate is the complement of the abnormal one."""
        if role in (ABNORMAL, HEALTHY):
            bad = value if role == ABNORMAL else not value
            out = []
            if bad and self.abnormal is not None:
                out.append((self.abnormal, obj))
            if not bad and self.healthy is not None:
                out.append((self.healthy, obj))
            for pred in (self.abnormal, self.healthy):
                comp = self.complements.get(pred or "")
                if comp is not None and (pred == self.abnormal) != bad:
                    out.append((comp, obj))
            return out
        pred = self.role(role)
        if pred is None:
            return []
        if value:
            return [(pred, obj)]
        comp = self.complements.get(pred)
        return [] if comp is None else [(comp, obj)]

    def predicates(self) -> set[str]:
        """Every predicate of the vocabulary, complements of them included."""
        words = {p for p in (self.abnormal, self.healthy, self.powered, self.running) if p}
        return words | {self.complements[p] for p in words if p in self.complements}

    def goal(self) -> tuple[str, bool]:
        """The goal for every component: ``(predicate, must hold)``: ``(good c)`` where the
        domain has a healthy word, else ``(not (ab c))``."""
        if self.healthy is not None:
            return self.healthy, True
        if self.abnormal is None:
            raise DomainError(*NO_HEALTH)
        return self.abnormal, False

    def require_health(self, where: str) -> None:
        """Raise ``DomainError`` when the domain cannot express a repair goal."""
        if self.abnormal is None and self.healthy is None:
            raise DomainError(f"{where}: {NO_HEALTH[0]}", NO_HEALTH[1])

    def switched_off(self, pred: str, positive: bool) -> bool:
        """Does a ``pred`` effect of this sign switch something off (power or running)?"""
        live = {p for p in (self.powered, self.running) if p is not None}
        if not positive:
            return pred in live
        return any(self.complements.get(p) == pred for p in live)


def infer(text: str, predicates: Mapping[str, int], where: str) -> Vocabulary:
    """The vocabulary of a domain: its declaration line, else the conventions above."""
    declared: dict[str, str] = {}
    negation = DEFAULT_NEGATION
    m = _DECLARATION.search(text)
    if m is not None:
        for item in m.group("body").split():
            key, eq, value = item.partition("=")
            if not eq or key not in (*ROLES, "negation") or not value:
                raise DomainError(
                    f"{where}: dxboard-vocabulary: cannot read {item!r}",
                    "write role=predicate with roles " + ", ".join((*ROLES, "negation")))
            if key == "negation":
                negation = value
            elif predicates.get(value) != 1:
                raise DomainError(
                    f"{where}: dxboard-vocabulary: {key}={value}, but the domain declares no "
                    f"predicate ({value} ?x)", "declare it in (:predicates ...) or fix the name")
            else:
                declared[key] = value
    roles: dict[str, str | None] = {}
    for role in ROLES:
        roles[role] = declared.get(role) or next(
            (p for p in INFERRED[role] if predicates.get(p) == 1), None)
    complements = {p: negation + p for p in predicates
                   if predicates.get(negation + p) == predicates[p]}
    return Vocabulary(roles[ABNORMAL], roles[HEALTHY], roles[POWERED], roles[RUNNING],
                      complements, tuple(sorted(declared)))
