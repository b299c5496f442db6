"""The Telerobot Diagnostic System's pipeline (paper 004 §4.3), event-driven: run on an alarm.

``explain_history`` wires the stages, each a function of the one before::

    history --alarm handler--> history up to the alarm (+ the alarm's atoms as observations)
            --sensor interpreter--> suspicion of fault modes from layer 0's diagnosis
            --context & plan interpreter--> Problem + the dispatcher's KB at every point
            --symptom identifier--> local and propagated symptoms
            --fault region identifier--> suspect faults (irrelevant steps not expanded)
            --plan-execution inference--> minimal diagnoses (engine: sat | tree | naive)
            --result--> ranked, classified alternative histories, corrected KB, plan error

The inference first searches the fault region; when that finds nothing (and was not cut by a
bound) it widens to the whole history, and says so. When nothing explains the observations,
the plan-error analysis says which condition the domain lacks. ``PlanDiagnoser`` keeps the
model and the settings for the mission layer, which calls ``on_alarm(history)``.
"""

from __future__ import annotations

import logging
import time
from dataclasses import dataclass
from typing import Any

from host.diagnosis.result import Bound
from host.plandiag.context import Context, Suspicion, interpret_context
from host.plandiag.engines import DEFAULT_ENGINE, ENGINES
from host.plandiag.errors import HistoryError
from host.plandiag.history import History
from host.plandiag.interpret import (
    AlarmNote,
    Symptom,
    handle_alarm,
    identify_symptoms,
    sensor_interpreter,
)
from host.plandiag.limits import ExplainOutcome, Limits
from host.plandiag.model import PlanModel
from host.plandiag.planerror import PlanError, analyse_plan_error
from host.plandiag.region import Region, fault_region
from host.plandiag.result import (
    AlternativeHistory,
    FaultClass,
    KbCorrection,
    correct_kb,
    rank,
)

log = logging.getLogger(__name__)


@dataclass
class Explanation:
    """Everything one diagnosis found, for ``dxboard explain``, the journal and the web page."""

    alarm: AlarmNote
    symptoms: list[Symptom]
    region: Region | None
    widened: bool
    engine: str
    outcome: ExplainOutcome
    histories: list[AlternativeHistory]
    kb: KbCorrection | None
    plan_error: PlanError | None
    context: Context
    suspicion: Suspicion
    elapsed_s: float

    def classes(self) -> list[FaultClass]:
        if self.plan_error is not None:
            return [FaultClass.PLAN_ERROR]
        return sorted({c for h in self.histories[:1] for c in h.classes()})

    def to_json(self) -> dict[str, Any]:
        p = self.context.problem
        return {
            "alarm": {**self.alarm.alarm.to_json(), "decision": self.alarm.decision.value,
                      "dropped_steps": self.alarm.dropped_steps},
            "symptoms": [{"kind": s.kind.value, "step": s.step, "where": s.where.value,
                          "text": s.text} for s in self.symptoms],
            "region": None if self.region is None else {
                "steps": list(self.region.steps), "expanded_steps": list(self.region.expanded),
                "suspects": len(self.region.suspects),
                "atoms": sorted(p.atom_name(a) for a in self.region.atoms)},
            "widened": self.widened,
            "engine": self.engine,
            "complete": self.outcome.complete,
            "cut_by": None if self.outcome.cut_by is None else self.outcome.cut_by.value,
            "explainable": bool(self.histories) or self.outcome.explainable,
            "classes": [c.value for c in self.classes()],
            "histories": [h.to_json() for h in self.histories],
            "kb": None if self.kb is None else self.kb.to_json(),
            "plan_error": None if self.plan_error is None else self.plan_error.to_json(),
            "cleared_modes": sorted(self.suspicion.cleared),
            "stats": {"nodes": self.outcome.nodes,
                      "inference_ms": round(self.outcome.elapsed_s * 1000, 3),
                      "total_ms": round(self.elapsed_s * 1000, 3)},
        }


def explain_history(model: PlanModel, history: History, engine: str = DEFAULT_ENGINE,
                    limits: Limits | None = None, use_region: bool = True) -> Explanation:
    """Diagnose ``history`` (a journal of executed steps ending in an alarm)."""
    if engine not in ENGINES:
        raise HistoryError(f"unknown engine {engine!r}", f"use one of {', '.join(ENGINES)}")
    limits = limits or Limits()
    start = time.perf_counter()
    history, note = handle_alarm(history)
    suspicion = sensor_interpreter(model, history.components)
    ctx = interpret_context(model, history, suspicion)
    symptoms = identify_symptoms(ctx, history)
    region = fault_region(ctx, symptoms) if use_region and symptoms else None
    run = ENGINES[engine]
    outcome = _timed(run, ctx, None if region is None else region.suspects, limits)
    widened = False
    if region is not None and not outcome.diagnoses and outcome.cut_by in (None, Bound.MAX_CARD):
        log.info("nothing explains the alarm inside the fault region: widening")
        outcome = _timed(run, ctx, None, limits)
        widened = True
    histories = rank(ctx.problem, outcome.diagnoses, limits.order, suspicion.confirmed)
    plan_error = None
    if not histories:
        plan_error = analyse_plan_error(model, ctx, history, proven=not outcome.explainable)
    last = ctx.problem.last_point
    kb = correct_kb(ctx.problem, ctx.kb[last], ctx.kb_after[last], histories)
    return Explanation(note, symptoms, region, widened, engine, outcome, histories, kb,
                       plan_error, ctx, suspicion, time.perf_counter() - start)


def _timed(run: Any, ctx: Context, universe: frozenset[int] | None,
           limits: Limits) -> ExplainOutcome:
    t0 = time.perf_counter()
    out: ExplainOutcome = run(ctx.problem, universe, limits)
    out.elapsed_s = time.perf_counter() - t0
    return out


class PlanDiagnoser:
    """The mission layer's handle: one model, one engine, diagnoses on every alarm."""

    def __init__(self, model: PlanModel, engine: str = DEFAULT_ENGINE,
                 limits: Limits | None = None) -> None:
        if engine not in ENGINES:
            raise ValueError(f"unknown engine {engine!r}; use one of {sorted(ENGINES)}")
        self.model = model
        self.engine = engine
        self.limits = limits or Limits()

    def on_alarm(self, history: History) -> Explanation:
        return explain_history(self.model, history, self.engine, self.limits)
