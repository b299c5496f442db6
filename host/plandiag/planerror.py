"""Plan errors: the plan ran as intended and could not have worked, because of the domain.

When no alternative history explains the observations (no fault mode, no event, in any
combination within the bounds), the history is simulated as intended to the first point
where it breaks: the *failing step*. If that step is a step that failed (or whose expected
state was not reached), the domain lacks a precondition that would have made the plan fail
in the model. The candidates are the literals over the step's own arguments that were false
in the state the step ran in and are not already part of its precondition, lifted to the
action's parameters: ``(not (locked ?d))`` when ``locked(door3)`` held. Earlier runs of the
same action that succeeded sort them: a candidate that was false at one of them cannot be
the missing condition (the action worked regardless) and is dropped; one true at all of them
is *supported*. Supported candidates come first, then properties no action changes (static
predicates), then the rest. If the history breaks at a precondition check instead, the atom
changed with nothing in the domain able to change it: an effect or an event is missing.
"""

from __future__ import annotations

import itertools
from dataclasses import dataclass
from typing import Any

from host.plandiag.context import Context
from host.plandiag.history import History, StepResult
from host.plandiag.model import PlanModel
from host.plandiag.problem import Stop, simulate
from host.planning.domain import ROOT_TYPE, CAnd, CAtom, CNot, Cond, Schema

MAX_CANDIDATES = 5


@dataclass(frozen=True)
class MissingCondition:
    literal: str  # lifted, PDDL: (not (locked ?d))
    ground: str  # as it stood at the failing step: locked(door3)
    supported_by: tuple[int, ...]  # earlier successful steps where it held
    static: bool

    def to_json(self) -> dict[str, Any]:
        return {"condition": self.literal, "held": self.ground,
                "supported_by_steps": list(self.supported_by), "static": self.static}


@dataclass(frozen=True)
class PlanError:
    step: int
    label: str
    reason: str
    conditions: tuple[MissingCondition, ...]
    proven: bool  # no diagnosis exists at all (else: none within the bounds)

    def to_json(self) -> dict[str, Any]:
        return {"step": self.step, "action": self.label, "reason": self.reason,
                "proven": self.proven,
                "missing_conditions": [c.to_json() for c in self.conditions]}


def analyse_plan_error(model: PlanModel, ctx: Context, history: History,
                       proven: bool) -> PlanError | None:
    p = ctx.problem
    run = simulate(p, ())
    if run.consistent:
        return None
    point = run.stop_point
    i = (point + 1) // 2
    spec = p.steps[i - 1]
    if point % 2 == 1 and run.stop is Stop.OBSERVATION:
        seen = run.detail.replace("it predicts", "the plan predicts")
        return PlanError(i, spec.label, f"at its precondition check {seen}, and no action, "
                         "fault mode or event of the domain explains the change: an effect or "
                         "an exogenous event is missing", (), proven)
    step = history.steps[i - 1]
    schema = model.actions[step.action]
    state = run.states[2 * i - 1] if len(run.states) > 2 * i - 1 else run.states[-1]
    earlier = [(k, s.args) for k, s in enumerate(history.steps[: i - 1], start=1)
               if s.action == step.action and s.result is StepResult.SUCCESS]
    found = []
    for cand in _candidates(model, ctx, schema, step.args, state):
        lifted, ground, positive, pred, idx = cand
        held = []
        refuted = False
        for k, args in earlier:
            s_k = run.states[2 * k - 1]
            value = _value(ctx, pred, tuple(args[j] for j in idx), s_k)
            if value == positive:
                held.append(k)
            else:
                refuted = True
                break
        if not refuted:
            found.append(MissingCondition(lifted, ground, tuple(held),
                                          pred in model.domain.statics))
    found.sort(key=lambda c: (not c.supported_by, not c.static, c.literal))
    what = {StepResult.FAIL: "reported failure", StepResult.HALTED: "was halted"}.get(
        step.result, "did not reach its expected state")
    reason = (f"it ran as intended and {what}; no fault mode or event explains it"
              + ("" if proven else " within the bounds"))
    return PlanError(i, spec.label, reason, tuple(found[:MAX_CANDIDATES]), proven)


def _value(ctx: Context, pred: str, args: tuple[str, ...], state: int) -> bool:
    a = ctx.problem.task.index.get((pred, args))
    return a is not None and bool((state >> a) & 1)


def _precondition_literals(c: Cond, out: set[tuple[str, tuple[str, ...], bool]]) -> None:
    if isinstance(c, CAnd):
        for x in c.args:
            _precondition_literals(x, out)
    elif isinstance(c, CAtom):
        out.add((c.atom.pred, c.atom.args, True))
    elif isinstance(c, CNot) and isinstance(c.arg, CAtom):
        out.add((c.arg.atom.pred, c.arg.atom.args, False))


def _candidates(model: PlanModel, ctx: Context, schema: Schema, args: tuple[str, ...],
                state: int) -> list[tuple[str, str, bool, str, tuple[int, ...]]]:
    """(lifted literal, the atom as it stood, sign, predicate, argument positions)."""
    pre: set[tuple[str, tuple[str, ...], bool]] = set()
    _precondition_literals(schema.precondition, pre)
    names = [v for v, _ in schema.parameters]
    types = [t for _, t in schema.parameters]
    out = []
    for pred, sig in sorted(model.domain.signatures.items()):
        pools = [[j for j, t in enumerate(types) if want in (ROOT_TYPE, t)
                  or want in model.domain.supertypes(t)] for want in sig]
        for idx in itertools.product(*pools):
            if len(set(idx)) < len(idx):
                continue  # (connected ?a ?a): not a condition anyone writes
            lifted_args = tuple(names[j] for j in idx)
            if (pred, lifted_args, True) in pre or (pred, lifted_args, False) in pre:
                continue
            ground_args = tuple(args[j] for j in idx)
            value = _value(ctx, pred, ground_args, state)
            atom = f"({pred}{''.join(' ' + a for a in lifted_args)})"
            lifted = f"(not {atom})" if value else atom
            ground = f"{pred}({','.join(ground_args)})"
            out.append((lifted, ground if value else "~" + ground, not value, pred, idx))
    return out
