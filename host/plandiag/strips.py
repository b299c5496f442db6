"""The mission layer's temporal domain read as plan-execution diagnosis reads it: STRIPS.

The mission layer plans with durative actions (``host.planning.temporal_pddl``); plan-execution
diagnosis explains histories of steps with preconditions and effects (``host.plandiag.model``).
One robot does one action at a time, so a durative action is one step: its **precondition** is
its start and over-all conditions and the end conditions its start effects do not establish;
its **effect** is its start effects followed by its end effects (an end effect overrides a
start effect on the same atom). ``strips_text`` writes that reading as PDDL text (typed STRIPS
with negative preconditions) for ``build_model``, so the mission's domain stays the one source:
``load_mission_model`` joins it with ``faults.pddl`` beside it (the fault modes and exogenous
events, written over the same types and predicates).
"""

from __future__ import annotations

from pathlib import Path

from host.plandiag.errors import PlanModelError
from host.plandiag.model import FAULTS_FILE, PlanModel, build_model
from host.planning.temporal_pddl import Action, Literal, TemporalDomain


def _lit(lit: Literal) -> str:
    atom, pos = lit
    text = "(" + " ".join(atom) + ")"
    return text if pos else f"(not {text})"


def _and(lits: list[Literal]) -> str:
    return "(and " + " ".join(_lit(x) for x in lits) + ")" if lits else "(and)"


def step_of(action: Action) -> tuple[list[Literal], list[Literal]]:
    """(precondition, effect) of a durative action read as one step."""
    start_eff = dict(action.eff.get("start", ()))
    pre = list(dict.fromkeys([*action.cond.get("start", ()), *action.cond.get("over all", ())]))
    pre += [c for c in action.cond.get("end", ())
            if start_eff.get(c[0]) != c[1] and c not in pre]
    eff: dict[tuple[str, ...], bool] = {}
    for atom, pos in [*action.eff.get("start", ()), *action.eff.get("end", ())]:
        eff[atom] = pos
    return pre, list(eff.items())


def strips_text(domain: TemporalDomain) -> str:
    types = " ".join(f"{t} - {p}" for t, p in domain.types.items())
    preds = " ".join("(" + " ".join([p, *(f"?x{i} - {t}" for i, t in enumerate(ts))]) + ")"
                     for p, ts in domain.predicates.items())
    out = [f"(define (domain {domain.name})",
           "  (:requirements :strips :typing :negative-preconditions)",
           f"  (:types {types})", f"  (:predicates {preds})"]
    for a in domain.actions.values():
        pre, eff = step_of(a)
        params = " ".join(f"{p} - {t}" for p, t in a.params)
        out += [f"  (:action {a.name}", f"    :parameters ({params})",
                f"    :precondition {_and(pre)}", f"    :effect {_and(eff)})"]
    return "\n".join(out) + ")\n"


def load_mission_model(domain: TemporalDomain, mission_dir: Path) -> PlanModel:
    """The plan model of a mission: its domain read as STRIPS, with ``faults.pddl`` of
    ``mission_dir`` (none there: no fault modes or events, every failure a plan error)."""
    faults = mission_dir / FAULTS_FILE
    try:
        faults_text = faults.read_text(encoding="utf-8") if faults.exists() else None
    except OSError as exc:
        raise PlanModelError(f"{faults}: cannot read the fault modes ({exc.strerror})",
                             "fix the file's permissions") from exc
    return build_model(strips_text(domain), faults_text, mission_dir / "domain.pddl",
                       faults if faults_text is not None else None)
