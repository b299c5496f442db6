"""Grounding: a lifted ``Domain`` + typed objects + static facts -> a ``Task``.

Stage two of the pipeline. Every action schema is instantiated with every type-correct
binding of its parameters; static predicates (those no action changes, e.g. ``needs``,
``protected``) are evaluated here, so an operator whose static precondition is false is never
built and the remaining preconditions are plain conjunctions of fluent literals. Quantifiers
are expanded: ``(forall (?c) (imply (needs ?n ?c) ...))`` and ``(forall (?n) (when (and
(needs ?n ?h) ...) ...))`` enumerate only the objects the static guard names (an index lookup,
not a scan of every object: this is what keeps grounding linear in the model size). A
disjunction over fluents that survives this is not supported (``DomainError`` names the
action). The result depends on the model only, never on a diagnosis.
"""

from __future__ import annotations

import itertools
import logging
from collections.abc import Iterable, Mapping
from dataclasses import dataclass

from host.planning.domain import (
    ROOT_TYPE,
    CAnd,
    CAtom,
    CForall,
    CNot,
    Cond,
    COr,
    Domain,
    EAnd,
    Eff,
    EForall,
    ELit,
    EWhen,
    PddlAtom,
    Schema,
)
from host.planning.errors import DomainError
from host.planning.task import CondEffect, GroundOp, Task, lit

log = logging.getLogger(__name__)

Binding = dict[str, str]
_FALSE = None  # a ground condition: None (false) or a list of fluent literals (their "and")


class _Unsupported(Exception):
    pass


@dataclass
class _Statics:
    facts: set[tuple[str, tuple[str, ...]]]
    by_pos: dict[tuple[str, int, str], list[tuple[str, ...]]]
    by_pred: dict[str, list[tuple[str, ...]]]

    @staticmethod
    def build(facts: Iterable[PddlAtom]) -> _Statics:
        s = _Statics(set(), {}, {})
        for f in facts:
            key = (f.pred, f.args)
            if key in s.facts:
                continue
            s.facts.add(key)
            s.by_pred.setdefault(f.pred, []).append(f.args)
            for i, a in enumerate(f.args):
                s.by_pos.setdefault((f.pred, i, a), []).append(f.args)
        return s


class Grounder:
    """Grounds one domain over one object set; ``ground()`` returns the ``Task``."""

    def __init__(self, domain: Domain, objects: Mapping[str, str], static: Iterable[PddlAtom]):
        self.domain = domain
        self.objects = dict(objects)
        self.statics = _Statics.build(static)
        self.static_preds = domain.statics
        self.task = Task([], {}, [])
        self._of_type: dict[str, list[str]] = {}
        for name, t in self.objects.items():
            for sup in (*domain.supertypes(t), ROOT_TYPE):
                self._of_type.setdefault(sup, []).append(name)
        self._is_a: dict[str, frozenset[str]] = {
            name: frozenset((*domain.supertypes(t), ROOT_TYPE)) for name, t in self.objects.items()
        }

    def of_type(self, type_name: str) -> list[str]:
        return self._of_type.get(type_name, [])

    def ground(self) -> Task:
        for schema in self.domain.schemas:
            pools = [self.of_type(t) for _, t in schema.parameters]
            for values in itertools.product(*pools):
                op = self.instantiate(schema, tuple(values))
                if op is not None:
                    self.task.ops.append(op)
        log.debug("grounded %d operators over %d atoms", len(self.task.ops), len(self.task.atoms))
        return self.task

    def instantiate(self, schema: Schema, values: tuple[str, ...]) -> GroundOp | None:
        """``schema`` with its parameters bound to ``values`` (in order), or None when a static
        precondition is false. Fluent atoms it mentions are numbered in ``self.task``."""
        b = dict(zip([v for v, _ in schema.parameters], values, strict=True))
        try:
            pre = self.cond(schema.precondition, b, False)
            if pre is _FALSE:
                return None
            eff: list[int] = []
            conds: list[CondEffect] = []
            self.effect(schema.effect, b, [], eff, conds)
        except _Unsupported as exc:
            raise DomainError(
                f"{self.domain.path}: action {schema.name}: {exc}",
                "keep disjunctions and existentials over static predicates only",
            ) from exc
        return GroundOp.make(schema.name, values, _dedup(pre), _dedup(eff), conds)

    # -- conditions -------------------------------------------------------------------------
    @staticmethod
    def _subst(atom: PddlAtom, b: Binding) -> tuple[str, ...]:
        return tuple([b.get(a, a) for a in atom.args])  # only variables are keys of b

    def cond(self, c: Cond, b: Binding, neg: bool) -> list[int] | None:
        """The ground condition (negated when ``neg``): None = false, [] = true."""
        if isinstance(c, CAtom):
            args = self._subst(c.atom, b)
            if c.atom.pred == "=":
                truth = args[0] == args[1]
            elif c.atom.pred in self.static_preds:
                truth = (c.atom.pred, args) in self.statics.facts
            else:
                return [lit(self.task.atom_id(c.atom.pred, args), not neg)]
            return [] if truth != neg else _FALSE
        if isinstance(c, CNot):
            return self.cond(c.arg, b, not neg)
        if (isinstance(c, CAnd) and not neg) or (isinstance(c, COr) and neg):
            out: list[int] = []
            for x in c.args:
                part = self.cond(x, b, neg)
                if part is _FALSE:
                    return _FALSE
                out += part
            return out
        if isinstance(c, CAnd | COr):
            return self._disj([self.cond(x, b, neg) for x in c.args], c)
        if neg:
            parts = [self.cond(c.body, bb, True) for bb in self._expand(c.variables, c.body, b)]
            return self._disj(parts, c)
        return self._conj(self.cond(c.body, bb, False) for bb in self._guarded(c, b))

    @staticmethod
    def _conj(parts: Iterable[list[int] | None]) -> list[int] | None:
        out: list[int] = []
        for p in parts:
            if p is _FALSE:
                return _FALSE
            out.extend(p)
        return out

    @staticmethod
    def _disj(parts: list[list[int] | None], c: object) -> list[int] | None:
        live = [p for p in parts if p is not _FALSE]
        if any(not p for p in live):
            return []
        if not live:
            return _FALSE
        if len(live) == 1:
            return live[0]
        raise _Unsupported(f"a disjunction over fluents remains after grounding: {c}")

    def _guarded(self, c: CForall, b: Binding) -> Iterable[Binding]:
        """Bindings of a universally quantified condition worth checking: when the body is
        ``(or (not static-guard) ...)`` only the objects the guard holds for can fail it."""
        if isinstance(c.body, COr):
            for d in c.body.args:
                if isinstance(d, CNot) and isinstance(d.arg, CAtom):
                    found = self._from_guard(d.arg.atom, c.variables, b)
                    if found is not None:
                        return found
        return self._expand(c.variables, c.body, b)

    def _from_guard(
        self, guard: PddlAtom, variables: tuple[tuple[str, str], ...], b: Binding
    ) -> list[Binding] | None:
        if guard.pred not in self.static_preds:
            return None
        names = {v for v, _ in variables}
        if not names <= set(guard.args):
            return None
        bound = [(i, b[a]) for i, a in enumerate(guard.args) if a in b and a not in names]
        bound += [(i, a) for i, a in enumerate(guard.args) if a[0] != "?"]
        if bound:
            i, value = bound[0]
            rows = self.statics.by_pos.get((guard.pred, i, value), [])
        else:
            rows = self.statics.by_pred.get(guard.pred, [])
        types = dict(variables)
        out: list[Binding] = []
        for row in rows:
            bb = dict(b)
            ok = True
            for a, v in zip(guard.args, row, strict=True):
                if a in names:
                    if bb.get(a, v) != v or types[a] not in self._is_a.get(v, ()):
                        ok = False
                        break
                    bb[a] = v
                elif (b.get(a, a) if a[0] == "?" else a) != v:
                    ok = False
                    break
            if ok:
                out.append(bb)
        return out

    def _expand(
        self, variables: tuple[tuple[str, str], ...], _body: object, b: Binding
    ) -> Iterable[Binding]:
        names = [v for v, _ in variables]
        for values in itertools.product(*(self.of_type(t) for _, t in variables)):
            bb = dict(b)
            bb.update(zip(names, values, strict=True))
            yield bb

    # -- effects ----------------------------------------------------------------------------
    def effect(
        self, e: Eff, b: Binding, under: list[int], eff: list[int], conds: list[CondEffect]
    ) -> None:
        if isinstance(e, ELit):
            x = lit(self.task.atom_id(e.atom.pred, self._subst(e.atom, b)), e.positive)
            if under:
                conds.append(CondEffect.make(_dedup(under), (x,)))
            else:
                eff.append(x)
        elif isinstance(e, EAnd):
            for part in e.args:
                self.effect(part, b, under, eff, conds)
        elif isinstance(e, EWhen):
            c = self.cond(e.cond, b, False)
            if c is not _FALSE:
                self.effect(e.body, b, under + c, eff, conds)
        else:
            for bb in self._effect_bindings(e, b):
                self.effect(e.body, bb, under, eff, conds)

    def _effect_bindings(self, e: EForall, b: Binding) -> Iterable[Binding]:
        """``forall`` effects whose body is ``when`` with a static guard in its condition
        enumerate the guard's objects only."""
        if isinstance(e.body, EWhen):
            c = e.body.cond
            parts = c.args if isinstance(c, CAnd) else (c,)
            for p in parts:
                if isinstance(p, CAtom):
                    found = self._from_guard(p.atom, e.variables, b)
                    if found is not None:
                        return found
        return self._expand(e.variables, e.body, b)


def _dedup(xs: list[int]) -> list[int]:
    return list(dict.fromkeys(xs))


def ground(domain: Domain, objects: Mapping[str, str], static: Iterable[PddlAtom]) -> Task:
    """Ground ``domain`` over ``objects`` (name -> type) and the true ``static`` facts."""
    unknown = sorted({t for t in objects.values()} - set(domain.types) - {ROOT_TYPE})
    if unknown:
        raise DomainError(
            f"{domain.path}: the model uses type(s) {', '.join(unknown)} the domain lacks",
            "declare them in (:types ...)",
        )
    return Grounder(domain, objects, static).ground()
