"""The original TEDUSAR (TU Graz) diagnosis model file: read it into a ``Theory``, write one back.

The format (paper 000 §IV-D) is YAML with five keys::

    ab: AB                 # the predicate of abnormality
    nab: NAB               # the predicate of health (NAB(x) is ~AB(x))
    neg_prefix: '!'        # a prefix that negates a literal ('~' and 'not ' work too)
    props: [AB(hokuyo_node), running(hokuyo_node), ok(/scan)]   # every proposition
    rules:
      - NAB(hokuyo_node) -> running(hokuyo_node)
      - NAB(hokuyo_node), NAB(hokuyo) -> ok(/scan)

A rule is ``body -> head``: the body a comma-separated conjunction of literals, the head one
literal. As an extension the head may be a disjunction (``a, b -> c | d``) or ``false``, and a
rule without ``->`` is a fact (a disjunction), so any clause set can be written, circuits
included; an empty head is an error (write ``false``). Components are the arguments of
``ab``/``nab`` atoms in props and rules. An optional ``priors: {component: p}`` key carries
prior fault probabilities. As in the original system, a rule may use atoms ``props`` does not
list: they are accepted, and the theory's one note names all of them.

Negation, as the original engine reads it (its C++ controller and Java prover in
``zinnirahkasim/tug_ist_model_based_diagnosis``): the prover knows no negation, ``not_a`` is an
atom like any other; the controller adds ``p, not_p -> false`` for each ``props`` entry and
sends an observation ``~a`` as the fact ``not_a``. So ``a`` and ``not_a`` exclude each other
only for the atoms ``props`` lists (read here as ``a`` and ``~a``); for an atom it does not list,
``not_a`` is an atom of its own (``Theory.separate``), and observing ``~a`` says nothing about
``a``. ``complement="all"`` reads ``not_a`` as ``~a`` everywhere (dxboard's earlier reading).
One difference is left: for a ``props`` entry the original only forbids both; here exactly one
holds (it matters only where a rule's body uses ``not_a`` of an atom nothing observes).

The January 2012 prototype format, ``props`` and ``rules`` as mappings (``rule1: NAB(a) ->
ok(x)``), is read in the file's order. Errors name the file, the line, the offending value
and the fix.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import yaml

from host.diagnosis import yamlpos
from host.diagnosis.logic import Clause, Literal, Theory, ab, ab_component, parse_literal
from host.errors import UserError

TUG_KEYS = {"ab", "nab", "neg_prefix", "props", "rules", "priors"}


def looks_like_tug(data: Any) -> bool:
    """True for parsed YAML whose top-level keys are those of the tug format."""
    return isinstance(data, dict) and "rules" in data and "props" in data


def read_tug(path: str | Path, complement: str = "props") -> Theory:
    """Load a tug model file. Raises ``UserError`` naming file and line."""
    file = Path(path)
    try:
        text = yamlpos.read_text(file)
    except yamlpos.YamlTooBig as exc:
        raise exc.to_user_error(file) from None
    except (OSError, UnicodeDecodeError) as exc:
        why = exc.strerror if isinstance(exc, OSError) else "not a UTF-8 text file"
        raise UserError(f"{file}: cannot read: {why}", "give a tug model file") from exc
    try:
        data, lines = yamlpos.load(text, typed=False)  # all strings
    except yamlpos.YamlSyntaxError as exc:
        raise UserError(f"{file}:{exc.line}: {exc}", exc.fix) from exc
    return parse_tug(data, lines, file, complement)


def _entries(value: Any) -> list[tuple[object, Any]] | None:
    """``(path key, item)`` of a list, or of a mapping (the January 2012 prototype format,
    ``props: {prop1: ok(x)}``, read in the file's order); None for anything else."""
    if isinstance(value, list):
        return list(enumerate(value))
    if isinstance(value, dict):
        return list(value.items())
    return None


def parse_tug(data: Any, lines: yamlpos.SourceLines, file: Path,
              complement: str = "props") -> Theory:
    """The theory of a parsed tug file. ``complement``: ``props`` (the original engine's
    reading, see the module docstring) or ``all`` (``not_a`` is ``~a`` for every atom)."""
    if complement not in ("props", "all"):
        raise ValueError(f"complement must be 'props' or 'all', not {complement!r}")
    def fail(path: tuple[object, ...], message: str, fix: str) -> UserError:
        return UserError(f"{file}:{lines(*path)}: {message}", fix)

    if not isinstance(data, dict):
        raise fail((), "not a tug model (a mapping with ab, nab, neg_prefix, props, rules)",
                    "see host/diagnosis/tug.py for the format")
    for key in data:
        if key not in TUG_KEYS:
            raise fail((key,), f"unknown key {key!r}", f"use one of {sorted(TUG_KEYS)}")
    ab_name = str(data.get("ab", "AB"))
    nab_name = str(data.get("nab", "NAB"))
    neg = data.get("neg_prefix") or "~"
    neg_prefixes = [str(neg)]
    components: dict[str, None] = {}

    seen: dict[str, Literal] = {}  # a model repeats its literals: parse each text once

    def literal(text: str, path: tuple[object, ...]) -> Literal:
        lit = seen.get(text)
        if lit is None:
            s = text.strip()
            lit = seen.get(s)
            if lit is None:
                lit = seen[s] = parse(s, text, path)
            seen[text] = lit
        return lit

    def parse(s: str, text: str, path: tuple[object, ...]) -> Literal:
        try:
            lit = parse_literal(s, neg_prefixes)
        except ValueError as exc:
            raise fail(path, str(exc), "write a literal such as ok(/scan) or !on(jaguar)") from exc
        if (own and not lit.positive and s.startswith(own) and lit.atom not in known
                and ab_component(lit.atom) is None and not s.startswith(own + own)):
            separate.setdefault(lit.atom)
            return Literal(own + lit.atom, True)
        for pred, sign in ((nab_name, False), (ab_name, True)):
            if lit.atom.startswith(pred + "(") and lit.atom.endswith(")"):
                comp = lit.atom[len(pred) + 1 : -1]
                if not comp:
                    raise fail(path, f"{text!r} names no component", f"write {pred}(name)")
                components.setdefault(comp)
                return Literal(ab(comp), lit.positive == sign)
        return lit

    props = _entries(data.get("props"))
    if props is None:
        raise fail(("props",), "props is not a list of propositions", "write props: [ok(/scan)]")
    known: dict[str, None] = {}
    own = ""  # set once props are read
    separate: dict[str, None] = {}
    for i, p in props:
        known.setdefault(literal(str(p), ("props", i)).atom)
    # from here on (the rules), an unlisted atom written with the model's prefix is an atom
    # of its own (not_a), as the original engine reads it
    own = str(neg).strip() if complement == "props" and str(neg).strip() not in (
        "~", "!", "-", "¬") else ""
    rules = _entries(data.get("rules"))
    if rules is None:
        raise fail(("rules",), "rules is not a list", "write rules: ['NAB(a) -> ok(x)']")
    clauses: list[Clause] = []
    negated: dict[str, Literal] = {}  # a body's text -> its literal, negated (parsed once)
    for i, rule in rules:
        path = ("rules", i)
        text = str(rule)
        body_text, arrow, head_text = text.partition("->")
        if not arrow:
            body_text, head_text = "", text
        lits: list[Literal] = []
        for t in body_text.split(","):
            lit = negated.get(t)
            if lit is None:
                if not t.strip():
                    continue
                lit = negated[t] = -literal(t, path)
            lits.append(lit)
        head_text = head_text.strip()
        if not head_text:
            raise fail(path, f"rule {text!r} has an empty head",
                       "write a literal after '->', or 'false' when the body cannot hold")
        if head_text.lower() == "false":
            if not arrow:
                raise fail(path, f"rule {text!r} says only false", "write body -> false")
        elif "|" in head_text:
            lits.extend(literal(t, path) for t in head_text.split("|"))
        else:
            lits.append(literal(head_text, path))
        clauses.append(Clause(tuple(lits)))
    # atoms rules use that props does not list, in the order rules first use them
    unlisted = {lit.atom: None for lit in seen.values()
                if lit.atom not in known and ab_component(lit.atom) is None
                and not (own and lit.atom.startswith(own) and lit.atom[len(own):] in separate)}
    if own:  # observing ~a of an unlisted atom a says not_a (as the original's controller)
        separate.update(unlisted)
    priors = data.get("priors") or {}
    if not isinstance(priors, dict):
        raise fail(("priors",), "priors is not a mapping", "write priors: {name: 0.01}")
    out_priors: dict[str, float] = {}
    for comp, p in priors.items():
        if str(comp) not in components:
            raise fail(("priors", comp), f"prior for unknown component {comp!r}",
                       f"use a component named in {ab_name}(...)")
        value = _number(p)
        if value is None or not 0 < value < 1:
            raise fail(("priors", comp), f"prior {p!r} is not in (0, 1)", "write e.g. 0.01")
        out_priors[str(comp)] = value
    notes: tuple[str, ...] = ()
    if unlisted:
        n = len(unlisted)
        them = "them" if n > 1 else "it"
        if own:
            how = (f"accepted as the original engine reads them: {own}X is an atom of its own, "
                   f"not complementary to X, and observing ~X says {own}X (add {them} to "
                   f"props to make {own}X the negation of X, and to silence this note)")
        else:
            how = f"accepted (add {them} to props to silence this note)"
        notes = (f"{file}: rules use {n} atom{'s' if n > 1 else ''} that props does not list: "
                 f"{', '.join(unlisted)}; {how}",)
    observables = frozenset(a for a in (*known, *unlisted) if ab_component(a) is None) | {
        own + a for a in separate}
    negations = tuple(p for p in neg_prefixes if p not in ("~", "!", "-", "¬"))
    return Theory(tuple(components), tuple(clauses), out_priors, observables, negations, notes,
                  frozenset(separate), own)


def _number(value: Any) -> float | None:
    """A prior read with or without YAML's implicit typing (``0.01`` or ``'0.01'``)."""
    if isinstance(value, bool):
        return None
    if isinstance(value, int | float):
        return float(value)
    try:
        return float(str(value))
    except ValueError:
        return None


def _rule(clause: Clause, ab_name: str, nab_name: str, neg: str) -> str:
    def name(atom: str, positive: bool) -> str:
        comp = ab_component(atom)
        if comp is not None:
            return f"{ab_name if positive else nab_name}({comp})"
        return atom if positive else neg + atom

    body = [name(lit.atom, not lit.positive) for lit in clause.lits
            if not lit.positive or ab_component(lit.atom) is not None]
    head = [lit.atom for lit in clause.lits
            if lit.positive and ab_component(lit.atom) is None]
    rhs = " | ".join(head) if head else "false"
    return f"{', '.join(body)} -> {rhs}" if body else rhs


def dump_tug(theory: Theory, ab_name: str = "AB", nab_name: str = "NAB", neg: str = "!") -> str:
    """The tug-format text of ``theory`` (priors only when they are set)."""
    props = [f"{ab_name}({c})" for c in theory.components]
    props += sorted(theory.observable_atoms() | {
        lit.atom for cl in theory.clauses for lit in cl.lits if ab_component(lit.atom) is None
    })
    data: dict[str, Any] = {
        "ab": ab_name,
        "nab": nab_name,
        "neg_prefix": neg,
        "props": props,
        "rules": [_rule(c, ab_name, nab_name, neg) for c in theory.clauses],
    }
    if theory.priors:
        data["priors"] = {c: float(p) for c, p in theory.priors.items()}
    dumper = getattr(yaml, "CSafeDumper", yaml.SafeDumper)
    return yaml.dump(data, Dumper=dumper, sort_keys=False, width=100, allow_unicode=True)


def write_tug(theory: Theory, path: str | Path) -> None:
    Path(path).write_text(dump_tug(theory), encoding="utf-8")
