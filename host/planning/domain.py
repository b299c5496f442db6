"""The repair domain: a PDDL file parsed by the ``pddl`` library into our lifted schemas.

Stage one of the planning pipeline (parse -> ground -> task -> search, after pyperplan). The
domain (``models/<robot>/repair.pddl``) is read by the ``pddl`` package (a real PDDL 3.1
parser) and converted once into small immutable values the grounder works on: ``Schema``
(an action with typed parameters, a precondition and an effect), ``Cond`` (and / or / not /
atom / forall over conditions; ``imply`` becomes ``or``) and ``Eff`` (literals, ``and``,
``forall``, ``when``). Supported: ``:strips :typing :negative-preconditions
:disjunctive-preconditions :universal-preconditions :conditional-effects`` (disjunctions must
vanish once static predicates are evaluated; the grounder says so if they do not). Predicates
that no action changes are *static* (``needs``, ``protected``); the others are *fluents*.
The domain's words for abnormal / healthy / powered / running (``Domain.vocabulary``) are read
from its ``; dxboard-vocabulary:`` line or inferred (``vocabulary.py``). Errors name the file
and what to change (``DomainError``).
"""

from __future__ import annotations

import logging
from collections.abc import Mapping
from dataclasses import dataclass, field
from functools import lru_cache
from pathlib import Path
from typing import Any, NamedTuple

from host.planning.errors import DomainError
from host.planning.vocabulary import Vocabulary, infer

log = logging.getLogger(__name__)

DOMAIN_FILE = "repair.pddl"
ROOT_TYPE = "object"
SUPPORTED_REQUIREMENTS = frozenset(
    {
        "strips",
        "typing",
        "negative-preconditions",
        "disjunctive-preconditions",
        "universal-preconditions",
        "conditional-effects",
        "equality",
    }
)


class PddlAtom(NamedTuple):
    """``pred(args)``; an argument starting with ``?`` is a variable. (A tuple: thousands
    are built and hashed per diagnosis.)"""

    pred: str
    args: tuple[str, ...]

    def __str__(self) -> str:
        return f"{self.pred}({','.join(self.args)})"


@dataclass(frozen=True)
class CAtom:
    atom: PddlAtom


@dataclass(frozen=True)
class CNot:
    arg: Cond


@dataclass(frozen=True)
class CAnd:
    args: tuple[Cond, ...]


@dataclass(frozen=True)
class COr:
    args: tuple[Cond, ...]


@dataclass(frozen=True)
class CForall:
    variables: tuple[tuple[str, str], ...]  # (?var, type)
    body: Cond


Cond = CAtom | CNot | CAnd | COr | CForall


@dataclass(frozen=True)
class ELit:
    atom: PddlAtom
    positive: bool


@dataclass(frozen=True)
class EAnd:
    args: tuple[Eff, ...]


@dataclass(frozen=True)
class EForall:
    variables: tuple[tuple[str, str], ...]
    body: Eff


@dataclass(frozen=True)
class EWhen:
    cond: Cond
    body: Eff


Eff = ELit | EAnd | EForall | EWhen


@dataclass(frozen=True)
class Schema:
    """One action of the domain, lifted."""

    name: str
    parameters: tuple[tuple[str, str], ...]  # (?var, type) in the file's order
    precondition: Cond
    effect: Eff


@dataclass(frozen=True)
class Domain:
    """A parsed repair domain: types (child -> parent), predicates (name -> arity), schemas."""

    name: str
    path: Path
    types: Mapping[str, str]
    predicates: Mapping[str, int]
    schemas: tuple[Schema, ...]
    fluents: frozenset[str]
    vocabulary: Vocabulary = field(default_factory=Vocabulary)
    # predicate -> the declared type of each argument (``object`` when untyped)
    signatures: Mapping[str, tuple[str, ...]] = field(default_factory=dict)

    @property
    def statics(self) -> frozenset[str]:
        return frozenset(self.predicates) - self.fluents

    def schema(self, name: str) -> Schema:
        for s in self.schemas:
            if s.name == name:
                return s
        raise KeyError(name)

    def supertypes(self, type_name: str) -> list[str]:
        """``type_name`` and every type above it, nearest first."""
        out = [type_name]
        while out[-1] in self.types and self.types[out[-1]] not in out:
            out.append(self.types[out[-1]])
        return out


def domain_file(system_dir: str | Path) -> Path:
    """``SYSTEM_DIR/repair.pddl`` (or the file itself when a file is given)."""
    p = Path(system_dir)
    return p / DOMAIN_FILE if p.is_dir() else p


def load_domain(path: str | Path) -> Domain:
    """Parse a PDDL domain file (cached by path and modification time, in this process and in
    the user's cache directory)."""
    file = domain_file(path)
    try:
        mtime = file.stat().st_mtime_ns
    except OSError as exc:
        raise DomainError(
            f"{file}: cannot read the repair domain ({exc.strerror})",
            f"write the domain as {DOMAIN_FILE} in the system directory or pass --domain FILE",
        ) from exc
    return _load_cached(file.resolve(), mtime)


@lru_cache(maxsize=16)
def _load_cached(file: Path, _mtime: int) -> Domain:
    return parse_domain_text(file.read_text(encoding="utf-8"), file)


@lru_cache(maxsize=32)
def parse_domain_text(text: str, path: Path = Path("<domain>")) -> Domain:
    """Parse PDDL domain text with the ``pddl`` library and convert it (the same text is
    parsed once: a new parser builds its grammar, ~0.3 s, and keeps state between calls; a
    new process reads text parsed before from the user's cache: ``domain_cache.py``)."""
    from host.planning.domain_cache import stored

    return stored(text, path, lambda: _parse_with_library(text, path))


def _parse_with_library(text: str, path: Path) -> Domain:
    from pddl.parser.domain import DomainParser

    try:
        parsed = DomainParser()(text)
    except Exception as exc:  # the library raises lark and its own errors alike
        first = str(exc).strip().splitlines()[0] if str(exc).strip() else type(exc).__name__
        raise DomainError(
            f"{path}: not a valid PDDL domain: {first}",
            "fix the PDDL syntax (the pddl library's message names the line and column)",
        ) from exc
    return _convert(parsed, path, text)


def _convert(parsed: Any, path: Path, text: str) -> Domain:
    reqs = {str(r).lstrip(":") for r in parsed.requirements}
    unsupported = sorted(reqs - SUPPORTED_REQUIREMENTS)
    if unsupported:
        raise DomainError(
            f"{path}: requirement(s) {', '.join(':' + r for r in unsupported)} are not supported",
            "use only " + " ".join(":" + r for r in sorted(SUPPORTED_REQUIREMENTS)),
        )
    types = {str(k): str(v) if v is not None else ROOT_TYPE for k, v in parsed.types.items()}
    predicates = {str(p.name): int(p.arity) for p in parsed.predicates}
    signatures = {
        str(p.name): tuple(_one_type(t, f"{path}: predicate {p.name}") for t in p.terms)
        for p in parsed.predicates
    }
    schemas = []
    for action in sorted(parsed.actions, key=lambda a: str(a.name)):
        where = f"{path}: action {action.name}"
        params = tuple((f"?{v.name}", _one_type(v, where)) for v in action.parameters)
        pre = _cond(action.precondition, where) if action.precondition is not None else CAnd(())
        eff = _eff(action.effect, where) if action.effect is not None else EAnd(())
        schemas.append(Schema(str(action.name), params, pre, eff))
    fluents: set[str] = set()
    for s in schemas:
        _collect_effect_preds(s.effect, fluents)
    unknown = sorted(fluents - set(predicates))
    if unknown:
        raise DomainError(
            f"{path}: effects use undeclared predicate(s) {', '.join(unknown)}",
            "declare them in (:predicates ...)",
        )
    vocabulary = infer(text, predicates, str(path))
    # what the problem layer sets from the observations varies with every diagnosis, even
    # where no action changes it (the original's stop_node reads running, which it never
    # sets): keep it a state atom, not a static fact of the grounding
    fluents |= vocabulary.predicates()
    log.debug("domain %s: %d actions, fluents %s, %s", parsed.name, len(schemas),
              sorted(fluents), vocabulary)
    return Domain(str(parsed.name), path, types, predicates, tuple(schemas), frozenset(fluents),
                  vocabulary, signatures)


def _one_type(term: Any, where: str) -> str:
    tags = sorted(str(t) for t in term.type_tags)
    if len(tags) > 1:
        raise DomainError(
            f"{where}: ?{term.name} has the type (either {' '.join(tags)})",
            "use a single type, or a common supertype",
        )
    return tags[0] if tags else ROOT_TYPE


def _atom(pred: Any) -> PddlAtom:
    args = []
    for t in pred.terms:
        name = str(t.name)
        args.append(f"?{name}" if type(t).__name__ == "Variable" else name)
    return PddlAtom(str(pred.name), tuple(args))


def _vars(variables: Any, where: str) -> tuple[tuple[str, str], ...]:
    return tuple(sorted((f"?{v.name}", _one_type(v, where)) for v in variables))


def _cond(f: Any, where: str) -> Cond:
    from pddl.logic import base, predicates

    if isinstance(f, predicates.Predicate):
        return CAtom(_atom(f))
    if isinstance(f, predicates.EqualTo):
        return CAtom(PddlAtom("=", (_term(f.left), _term(f.right))))
    if isinstance(f, base.Not):
        return CNot(_cond(f.argument, where))
    if isinstance(f, base.And):
        return CAnd(tuple(_cond(x, where) for x in f.operands))
    if isinstance(f, base.Or):
        return COr(tuple(_cond(x, where) for x in f.operands))
    if isinstance(f, base.Imply):
        *lhs, rhs = f.operands
        return COr((*(CNot(_cond(x, where)) for x in lhs), _cond(rhs, where)))
    if isinstance(f, base.ForallCondition):
        return CForall(_vars(f.variables, where), _cond(f.condition, where))
    raise DomainError(
        f"{where}: the condition {f} is not supported",
        "use and/or/not/imply/forall over predicates",
    )


def _term(t: Any) -> str:
    return f"?{t.name}" if type(t).__name__ == "Variable" else str(t.name)


def _eff(f: Any, where: str) -> Eff:
    from pddl.logic import base, effects, predicates

    if isinstance(f, predicates.Predicate):
        return ELit(_atom(f), True)
    if isinstance(f, base.Not) and isinstance(f.argument, predicates.Predicate):
        return ELit(_atom(f.argument), False)
    if isinstance(f, base.And):
        return EAnd(tuple(_eff(x, where) for x in f.operands))
    if isinstance(f, effects.Forall):
        return EForall(_vars(f.variables, where), _eff(f.effect, where))
    if isinstance(f, effects.When):
        return EWhen(_cond(f.condition, where), _eff(f.effect, where))
    raise DomainError(
        f"{where}: the effect {f} is not supported",
        "use literals, and, forall and when (no numeric or probabilistic effects)",
    )


def _collect_effect_preds(e: Eff, out: set[str]) -> None:
    if isinstance(e, ELit):
        out.add(e.atom.pred)
    elif isinstance(e, EAnd):
        for x in e.args:
            _collect_effect_preds(x, out)
    else:
        _collect_effect_preds(e.body, out)
