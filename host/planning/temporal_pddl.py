"""Temporal PDDL (PDDL 2.1 durative actions, the subset the mission layer plans with): parsing.

The ``pddl`` library the repair engine uses does not parse durative actions (it stops at the
``:durative-actions`` requirement), so the mission layer reads its own small subset::

    (define (domain NAME)
      (:requirements :strips :typing :negative-preconditions :durative-actions)
      (:types room door - place ...)
      (:predicates (at ?r - room) ...)
      (:durative-action NAME
        :parameters (?a - room ?b - room)
        :duration (= ?duration 8)
        :condition (and (at start (at ?a)) (over all (open ?d)) (at end ...))
        :effect (and (at start (not (at ?a))) (at end (at ?b)))))
    (define (problem NAME) (:domain NAME)
      (:objects entrance office - room ...)
      (:init (at entrance) ...)
      (:goal (and (searched office) ...)))

Conditions are literals at start, over all or at end; effects literals at start or at end;
``(not ...)`` negates; ``:action`` (instantaneous) is read as a durative action of duration 0
with its precondition at start and its effect at end. Atoms are tuples ``("at", "office")``,
spelled ``(at office)`` (``spell``). A mistake is a ``PddlError`` naming the file, the line and
the fix.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

Atom = tuple[str, ...]
Literal = tuple[Atom, bool]  # (atom, positive)

SUPPORTED = {":strips", ":typing", ":negative-preconditions", ":durative-actions"}
WHEN_COND = {("at", "start"): "start", ("over", "all"): "over all", ("at", "end"): "end"}


class PddlError(ValueError):
    """The PDDL text is wrong or outside the subset; the message says where and how to fix it."""


@dataclass(frozen=True)
class Token:
    text: str
    line: int




@dataclass(frozen=True)
class Action:
    name: str
    params: tuple[tuple[str, str], ...]  # (?x, type)
    duration: float
    cond: dict[str, tuple[Literal, ...]]  # "start" / "over all" / "end" -> literals
    eff: dict[str, tuple[Literal, ...]]  # "start" / "end" -> literals

    @property
    def param_names(self) -> tuple[str, ...]:
        return tuple(p for p, _ in self.params)


@dataclass
class TemporalDomain:
    name: str
    types: dict[str, str] = field(default_factory=dict)  # type -> parent ("object" at the top)
    predicates: dict[str, tuple[str, ...]] = field(default_factory=dict)  # name -> arg types
    actions: dict[str, Action] = field(default_factory=dict)

    def is_a(self, typ: str, ancestor: str) -> bool:
        while True:
            if typ == ancestor:
                return True
            if typ not in self.types:
                return ancestor == "object"
            typ = self.types[typ]


@dataclass
class TemporalProblem:
    name: str
    domain: str
    objects: dict[str, str]  # object -> type
    init: frozenset[Atom]
    goal: tuple[Literal, ...]


def spell(atom: Atom) -> str:
    return "(" + " ".join(atom) + ")"


def parse_atom(text: str) -> Atom:
    """``(at office)`` -> ``("at", "office")``; ``PddlError`` if it is not a ground atom."""
    parts = text.strip()
    if not (parts.startswith("(") and parts.endswith(")")):
        raise PddlError(f"{text!r} is not an atom like (at office)")
    words = parts[1:-1].split()
    if not words or any(c in w for w in words for c in "()"):
        raise PddlError(f"{text!r} is not an atom like (at office)")
    return tuple(w.lower() for w in words)


# --- reading --------------------------------------------------------------------------------

def _tokens(text: str) -> list[Token]:
    out: list[Token] = []
    for n, line in enumerate(text.splitlines(), 1):
        line = line.split(";", 1)[0]
        for word in line.replace("(", " ( ").replace(")", " ) ").split():
            out.append(Token(word.lower(), n))
    return out


def _read(tokens: list[Token], where: str) -> list[object]:
    stack: list[list[object]] = [[]]
    opened: list[int] = []
    for tok in tokens:
        if tok.text == "(":
            stack.append([])
            opened.append(tok.line)
        elif tok.text == ")":
            if len(stack) == 1:
                raise PddlError(f"{where}:{tok.line}: a ')' too many")
            done = stack.pop()
            opened.pop()
            stack[-1].append(done)
        else:
            stack[-1].append(tok)
    if len(stack) > 1:
        raise PddlError(f"{where}:{opened[-1]}: this '(' is never closed")
    if len(stack[0]) != 1 or not isinstance(stack[0][0], list):
        raise PddlError(f"{where}: expected one (define ...)")
    return stack[0][0]


def _line(x: object) -> int:
    if isinstance(x, Token):
        return x.line
    if isinstance(x, list):
        for y in x:
            n = _line(y)
            if n:
                return n
    return 0


def _word(x: object, where: str, what: str) -> str:
    if not isinstance(x, Token):
        raise PddlError(f"{where}:{_line(x)}: expected {what}")
    return x.text


def _typed(items: list[object], where: str) -> list[tuple[str, str]]:
    """``a b - t c`` -> [(a, t), (b, t), (c, object)]."""
    out: list[tuple[str, str]] = []
    pending: list[str] = []
    i = 0
    while i < len(items):
        w = _word(items[i], where, "a name")
        if w == "-":
            if i + 1 >= len(items) or not pending:
                raise PddlError(f"{where}:{_line(items[i])}: '-' must sit between names and "
                                "their type")
            typ = _word(items[i + 1], where, "a type")
            out += [(p, typ) for p in pending]
            pending = []
            i += 2
            continue
        pending.append(w)
        i += 1
    return out + [(p, "object") for p in pending]


def _literal(x: object, where: str) -> Literal:
    if not isinstance(x, list) or not x:
        raise PddlError(f"{where}:{_line(x)}: expected a literal like (at ?r) or (not (at ?r))")
    head = _word(x[0], where, "a predicate")
    if head == "not":
        if len(x) != 2:
            raise PddlError(f"{where}:{_line(x)}: (not ...) takes one atom")
        atom, pos = _literal(x[1], where)
        if not pos:
            raise PddlError(f"{where}:{_line(x)}: (not (not ...)) is not supported")
        return atom, False
    return (head, *(_word(a, where, "an argument") for a in x[1:])), True


def _conjuncts(x: object, where: str) -> list[object]:
    if isinstance(x, list) and x and isinstance(x[0], Token) and x[0].text == "and":
        return list(x[1:])
    return [x]


def _timed(x: object, where: str, allowed: dict[tuple[str, str], str],
           what: str) -> dict[str, list[Literal]]:
    out: dict[str, list[Literal]] = {w: [] for w in allowed.values()}
    for c in _conjuncts(x, where):
        if not isinstance(c, list) or len(c) != 3:
            raise PddlError(f"{where}:{_line(c)}: a {what} is (at start L), (over all L) or "
                            "(at end L)")
        key = (_word(c[0], where, "at/over"), _word(c[1], where, "start/all/end"))
        if key not in allowed:
            raise PddlError(f"{where}:{_line(c)}: ({' '.join(key)} ...) is not a {what} here "
                            f"(use {', '.join('(' + ' '.join(k) + ' ...)' for k in allowed)})")
        out[allowed[key]].append(_literal(c[2], where))
    return out


def _action(x: list[object], where: str, durative: bool) -> Action:
    name = _word(x[1], where, "an action name")
    fields: dict[str, object] = {}
    i = 2
    while i + 1 < len(x):
        fields[_word(x[i], where, "a :field")] = x[i + 1]
        i += 2
    if i < len(x):
        raise PddlError(f"{where}:{_line(x[i])}: {name}: a field without a value")
    raw_params = fields.get(":parameters", [])
    if not isinstance(raw_params, list):
        raise PddlError(f"{where}:{_line(x)}: {name}: :parameters must be a list")
    params = tuple(_typed(raw_params, where))
    if durative:
        dur = fields.get(":duration")
        if not (isinstance(dur, list) and len(dur) == 3 and _word(dur[0], where, "=") == "="
                and _word(dur[1], where, "?duration") == "?duration"):
            raise PddlError(f"{where}:{_line(x)}: {name}: give :duration (= ?duration N)")
        try:
            duration = float(_word(dur[2], where, "a number"))
        except ValueError:
            raise PddlError(f"{where}:{_line(dur)}: {name}: the duration must be a number "
                            "(numeric fluents are not supported)") from None
        cond = _timed(fields.get(":condition", []), where, WHEN_COND, "condition")
        eff = _timed(fields.get(":effect", []), where,
                     {("at", "start"): "start", ("at", "end"): "end"}, "timed effect")
    else:
        duration = 0.0
        pre = [_literal(c, where) for c in _conjuncts(fields.get(":precondition", []), where)
               if c != []]
        post = [_literal(c, where) for c in _conjuncts(fields.get(":effect", []), where)
                if c != []]
        cond = {"start": pre, "over all": [], "end": []}
        eff = {"start": [], "end": post}
    variables = {p for p, _ in params}
    for lits in (*cond.values(), *eff.values()):
        for atom, _ in lits:
            for arg in atom[1:]:
                if arg.startswith("?") and arg not in variables:
                    raise PddlError(f"{where}:{_line(x)}: {name}: {arg} is not a parameter")
    return Action(name, params, duration, {k: tuple(v) for k, v in cond.items()},
                  {k: tuple(v) for k, v in eff.items()})


def _sections(tree: list[object], kind: str, where: str) -> tuple[str, list[list[object]]]:
    if len(tree) < 2 or _word(tree[0], where, "define") != "define" \
            or not isinstance(tree[1], list) or len(tree[1]) != 2 \
            or _word(tree[1][0], where, kind) != kind:
        raise PddlError(f"{where}:{_line(tree)}: expected (define ({kind} NAME) ...)")
    sections = [s for s in tree[2:] if isinstance(s, list) and s]
    return _word(tree[1][1], where, "a name"), sections


def parse_domain(text: str, where: str = "domain.pddl") -> TemporalDomain:
    name, sections = _sections(_read(_tokens(text), where), "domain", where)
    dom = TemporalDomain(name)
    for sec in sections:
        head = _word(sec[0], where, "a :section")
        if head == ":requirements":
            for r in sec[1:]:
                if _word(r, where, "a requirement") not in SUPPORTED:
                    raise PddlError(f"{where}:{_line(r)}: requirement {_word(r, where, '')} is "
                                    f"not supported (supported: {', '.join(sorted(SUPPORTED))})")
        elif head == ":types":
            dom.types.update(dict(_typed(sec[1:], where)))
        elif head == ":predicates":
            for p in sec[1:]:
                if not isinstance(p, list) or not p:
                    raise PddlError(f"{where}:{_line(p)}: a predicate is (name ?x - type ...)")
                dom.predicates[_word(p[0], where, "a predicate")] = tuple(
                    t for _, t in _typed(p[1:], where))
        elif head in (":durative-action", ":action"):
            act = _action(sec, where, head == ":durative-action")
            dom.actions[act.name] = act
        else:
            raise PddlError(f"{where}:{_line(sec)}: section {head} is not supported here")
    for act in dom.actions.values():
        for lits in (*act.cond.values(), *act.eff.values()):
            for atom, _ in lits:
                if atom[0] not in dom.predicates:
                    raise PddlError(f"{where}: action {act.name}: predicate {atom[0]} is not "
                                    "declared in :predicates")
    return dom


def parse_problem(text: str, domain: TemporalDomain,
                  where: str = "problem.pddl") -> TemporalProblem:
    name, sections = _sections(_read(_tokens(text), where), "problem", where)
    objects: dict[str, str] = {}
    init: set[Atom] = set()
    goal: list[Literal] = []
    dom_name = ""
    for sec in sections:
        head = _word(sec[0], where, "a :section")
        if head == ":domain":
            dom_name = _word(sec[1], where, "a domain name")
        elif head == ":objects":
            objects.update(dict(_typed(sec[1:], where)))
        elif head == ":init":
            for a in sec[1:]:
                atom, pos = _literal(a, where)
                if not pos:
                    raise PddlError(f"{where}:{_line(a)}: :init lists true atoms only")
                init.add(atom)
        elif head == ":goal":
            goal += [_literal(c, where) for c in _conjuncts(sec[1], where) if c != []]
        else:
            raise PddlError(f"{where}:{_line(sec)}: section {head} is not supported here")
    if dom_name != domain.name:
        raise PddlError(f"{where}: (:domain {dom_name or '?'}) is not {domain.name}")
    for typ in objects.values():
        if typ != "object" and typ not in domain.types:
            raise PddlError(f"{where}: type {typ} is not declared in the domain's :types")
    for atom in [*init, *(a for a, _ in goal)]:
        if atom[0] not in domain.predicates:
            raise PddlError(f"{where}: {spell(atom)}: no predicate {atom[0]} in the domain")
        unknown = [a for a in atom[1:] if a not in objects]
        if unknown:
            raise PddlError(f"{where}: {spell(atom)}: {unknown[0]} is not an object")
    return TemporalProblem(name, dom_name, objects, frozenset(init), tuple(goal))


def load(domain_file: Path, problem_file: Path) -> tuple[TemporalDomain, TemporalProblem]:
    try:
        dom_text, prob_text = domain_file.read_text(), problem_file.read_text()
    except OSError as exc:
        raise PddlError(f"{exc.filename}: cannot read ({exc.strerror})") from None
    domain = parse_domain(dom_text, str(domain_file))
    return domain, parse_problem(prob_text, domain, str(problem_file))
