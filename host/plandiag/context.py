"""Context & plan interpreter (paper 004 §4.3.1.3): the history with the domain, step by step.

``interpret_context`` grounds every executed step's action, the fault modes that may replace it
and the exogenous events that may happen in each gap (through ``host.planning.grounding``, with
the static facts of the initial knowledge base), checks the history against the domain (every
action, object, type and atom is known; ``HistoryError`` names the place otherwise), and returns
the ``HistoryProblem`` the engines search together with the knowledge base the dispatcher held at
every point: ROSPlan-like, it applies a step's effects after a reported success only, and an
observation overrides what it says. Fault modes whose components layer 0 shows working are left
out (``Suspicion``); those of a broken component get ``BROKEN_PRIOR``. A mode with extra
parameters (where ``navigate`` really ended) shares its prior among its groundings.
"""

from __future__ import annotations

import itertools
import logging
from collections.abc import Mapping
from dataclasses import dataclass, field

from host.atoms import Atom
from host.plandiag.errors import HistoryError
from host.plandiag.history import History, StepResult, Where
from host.plandiag.model import FaultKind, FaultSchema, PlanModel
from host.plandiag.problem import Fault, HistoryProblem, StepSpec
from host.planning.domain import ROOT_TYPE, PddlAtom
from host.planning.errors import DomainError
from host.planning.grounding import Grounder
from host.planning.task import GroundOp, Task

log = logging.getLogger(__name__)

#: the prior of a fault mode one of whose components layer 0 diagnosed broken
BROKEN_PRIOR = 0.9


@dataclass(frozen=True)
class Suspicion:
    """What the sensor interpreter made of layer 0's diagnosis, per fault-mode schema."""

    cleared: Mapping[str, tuple[str, ...]] = field(default_factory=dict)  # all shown working
    confirmed: Mapping[str, tuple[str, ...]] = field(default_factory=dict)  # broken ones

    def prior(self, fs: FaultSchema) -> float | None:
        """The prior to use, or None when the mode is out of suspicion."""
        if fs.name in self.confirmed:
            return max(fs.prior, BROKEN_PRIOR)
        if fs.name in self.cleared:
            return None
        return fs.prior


@dataclass
class Context:
    """The compiled history: the ``HistoryProblem`` and the dispatcher's knowledge base per
    point."""

    problem: HistoryProblem
    kb: list[int]  # point -> the KB before that point's observations
    kb_after: list[int]  # point -> the KB after them
    observed: dict[int, list[tuple[int, bool, str]]]  # point -> (atom, value, where)
    grounder: Grounder


def interpret_context(model: PlanModel, history: History, suspicion: Suspicion) -> Context:
    domain = model.domain
    _check_objects(model, history)
    statics = [PddlAtom(a.predicate, a.args) for a in history.init
               if a.predicate in domain.statics]
    try:
        grounder = Grounder(domain, history.objects, statics)
    except DomainError as exc:  # pragma: no cover - the model was checked when loaded
        raise HistoryError(exc.message, exc.hint) from exc
    task = grounder.task
    init = 0
    for fact in sorted(history.init):
        _check_atom(model, history, fact, "init")
        init |= 1 << task.atom_id(fact.predicate, fact.args)
    faults: list[Fault] = []
    steps: list[StepSpec] = []
    observed: dict[int, list[tuple[int, bool, str]]] = {}
    obs: dict[int, tuple[int, int]] = {}
    for i, step in enumerate(history.steps, start=1):
        place = f"steps[{i - 1}]"
        schema = model.actions.get(step.action)
        if schema is None:
            raise HistoryError(f"{place}: unknown action {step.action!r}",
                               f"the mission domain has {', '.join(sorted(model.actions))}")
        _check_args(model, history, schema.parameters, step.args, place)
        nominal = grounder.instantiate(schema, step.args)
        if nominal is not None and step.result is StepResult.FAIL:
            nominal = None  # it ran and failed: not as intended
        elif nominal is not None and step.result is StepResult.HALTED:
            nominal = GroundOp.make(nominal.name, nominal.args, (), ())  # stopped: unknown
        modes: list[int] = []
        if step.executed():
            for fs in model.modes.get(step.action, ()):
                prior = suspicion.prior(fs)
                if prior is not None:
                    modes += _ground_mode(grounder, fs, prior, i, step.args, faults)
        steps.append(StepSpec(i, step.label(), nominal, tuple(modes), step.executed()))
        for j, o in enumerate(step.observations):
            _check_atom(model, history, o.atom, f"{place}.observations[{j}].atom")
            point = 2 * i - 1 if o.where is Where.PRE else 2 * i
            a = task.atom_id(o.atom.predicate, o.atom.args)
            observed.setdefault(point, []).append((a, o.value, o.where.value))
            t, f = obs.get(point, (0, 0))
            if (o.value and (f >> a) & 1) or (not o.value and (t >> a) & 1):
                raise HistoryError(f"{place}.observations[{j}]: {o.atom} is observed both true "
                                   f"and false at {o.where.value}",
                                   "keep the observation the sensors trust")
            obs[point] = (t | (1 << a), f) if o.value else (t, f | (1 << a))
    gaps = _ground_events(grounder, model, len(steps), faults)
    last = 2 * len(steps) - (0 if not steps or steps[-1].executed else 1)
    problem = HistoryProblem(task, init, steps, gaps, faults, obs, max(last, 0))
    kb, kb_after = _dispatcher_kb(problem, history)
    log.debug("context: %d steps, %d atoms, %d faults", len(steps), len(task.atoms), len(faults))
    return Context(problem, kb, kb_after, observed, grounder)


def _ground_mode(grounder: Grounder, fs: FaultSchema, prior: float, step: int,
                 args: tuple[str, ...], faults: list[Fault]) -> list[int]:
    extra = fs.schema.parameters[len(args):]
    ops = []
    for values in itertools.product(*(grounder.of_type(t) for _, t in extra)):
        op = grounder.instantiate(fs.schema, args + tuple(values))
        if op is not None:
            ops.append(op)
    out = []
    for op in ops:
        out.append(len(faults))
        faults.append(Fault(len(faults), FaultKind.MODE, step, op, prior / len(ops),
                            fs.mode_of, fs.components))
    return out


def _ground_events(grounder: Grounder, model: PlanModel, n_steps: int,
                   faults: list[Fault]) -> list[tuple[int, ...]]:
    ground: list[tuple[GroundOp, FaultSchema]] = []
    for fs in model.events:
        pools = [grounder.of_type(t) for _, t in fs.schema.parameters]
        for values in itertools.product(*pools):
            op = grounder.instantiate(fs.schema, tuple(values))
            if op is not None:
                ground.append((op, fs))
    gaps: list[tuple[int, ...]] = []
    for gap in range(1, n_steps + 1):
        ids = []
        for op, fs in ground:
            ids.append(len(faults))
            faults.append(Fault(len(faults), FaultKind.EVENT, gap, op, fs.prior, None,
                                fs.components))
        gaps.append(tuple(ids))
    return gaps


def _dispatcher_kb(problem: HistoryProblem, history: History) -> tuple[list[int], list[int]]:
    """What the dispatcher believed at every point: effects applied after a reported
    success, observations overriding (sensing)."""
    kb = [problem.init]
    after = [_override(problem, 0, problem.init)]
    state = after[0]
    for spec, step in zip(problem.steps, history.steps, strict=True):
        kb.append(state)  # the gap: the dispatcher knows of no events
        state = _override(problem, 2 * spec.index - 1, state)
        after.append(state)
        if not spec.executed:
            break
        if step.result is StepResult.SUCCESS and spec.nominal is not None:
            state = spec.nominal.apply(state)
        kb.append(state)
        state = _override(problem, 2 * spec.index, state)
        after.append(state)
    return kb, after


def _override(problem: HistoryProblem, point: int, state: int) -> int:
    t, f = problem.obs.get(point, (0, 0))
    return (state & ~f) | t


# -- checks ---------------------------------------------------------------------------------
def _check_objects(model: PlanModel, history: History) -> None:
    known = set(model.domain.types) | {ROOT_TYPE}
    for name, t in history.objects.items():
        if t not in known:
            raise HistoryError(f"objects.{name}: unknown type {t!r}",
                               f"the mission domain has {', '.join(sorted(known))}")


def _is_a(model: PlanModel, obj_type: str, want: str) -> bool:
    return want == ROOT_TYPE or want in model.domain.supertypes(obj_type)


def _check_args(model: PlanModel, history: History, params: tuple[tuple[str, str], ...],
                args: tuple[str, ...], place: str) -> None:
    if len(args) != len(params):
        raise HistoryError(f"{place}.args: {len(args)} arguments, the action takes "
                           f"{len(params)}", "give one argument per parameter, in order: "
                           + " ".join(f"{v} - {t}" for v, t in params))
    for (var, want), arg in zip(params, args, strict=True):
        _check_object(model, history, arg, want, f"{place}.args",
                      f"{var} must be a {want}", "pass an object of the parameter's type")


def _check_atom(model: PlanModel, history: History, a: Atom, place: str) -> None:
    sig = model.domain.signatures.get(a.predicate)
    if sig is None or len(sig) != len(a.args):
        arity = model.domain.predicates.get(a.predicate)
        what = "unknown predicate" if arity is None else f"takes {arity} arguments"
        raise HistoryError(f"{place}: {a}: {what}",
                           "use the mission domain's predicates: " + ", ".join(
                               f"{p}/{n}" for p, n in sorted(model.domain.predicates.items())))
    for want, arg in zip(sig, a.args, strict=True):
        _check_object(model, history, arg, want, f"{place}: {a}", f"not a {want}",
                      "use objects of the predicate's types")


def _check_object(model: PlanModel, history: History, arg: str, want: str, where: str,
                  wrong: str, fix: str) -> None:
    """``arg`` is a listed object of type ``want`` (or a subtype), or one line says not."""
    t = history.objects.get(arg)
    if t is None:
        raise HistoryError(f"{where}: unknown object {arg!r}",
                           "list every object with its type under \"objects\"")
    if not _is_a(model, t, want):
        raise HistoryError(f"{where}: {arg} is a {t}, {wrong}", fix)


def state_atoms(task: Task, state: int) -> list[str]:
    return [f"{p}({','.join(a)})" for i, (p, a) in enumerate(task.atoms) if (state >> i) & 1]
