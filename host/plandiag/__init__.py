"""Plan-execution diagnosis (paper 004's Telerobot Diagnostic System, paper 001's history-based
diagnosis): why a mission step failed, from the plan and its execution.

A mission domain (``mission.pddl``) with its fault modes and exogenous events (``faults.pddl``,
annotated) becomes a ``PlanModel`` (``load_model``); an executed history (``history.json``, the
mission journal's record) a ``History`` (``load_history``). ``explain_history`` runs the TDS
pipeline of pure stages — alarm handler, sensor interpreter, context & plan interpreter,
symptom identifier, fault region identifier, plan-execution inference — and returns an
``Explanation``: the minimal alternative histories ranked and classified, the corrected
knowledge base, or the plan error and the condition the domain lacks. The inference engines
(``ENGINES``: the context tree, SAT, naive enumeration) return the same minimal diagnoses::

    model = load_model("tests/plandiag/arena")
    explanation = explain_history(model, load_history("history.json"))
    print("\\n".join(render(explanation)))

In the running mission, ``strips`` reads the mission layer's temporal domain as STRIPS (with
the ``faults.pddl`` beside it) and ``live.MissionDiagnoser`` records the executed history from
the dispatcher's events and sensing, explains it on an alarm (a ``PlanDiagnosis`` event) and
gives the mission the knowledge base's corrections to replan from.
"""

from host.plandiag.engines import DEFAULT_ENGINE, ENGINES
from host.plandiag.errors import HistoryError, PlanModelError
from host.plandiag.history import (
    Alarm,
    ComponentHealth,
    History,
    HistoryStep,
    MissionObservation,
    StepResult,
    Where,
    history_from_json,
    load_history,
)
from host.plandiag.interpret import Decision, alarm_decision
from host.plandiag.limits import Limits, Order
from host.plandiag.model import FaultKind, PlanModel, build_model, load_model
from host.plandiag.pipeline import Explanation, PlanDiagnoser, explain_history
from host.plandiag.result import FaultClass
from host.plandiag.text import render

__all__ = [
    "DEFAULT_ENGINE",
    "ENGINES",
    "Alarm",
    "ComponentHealth",
    "Decision",
    "Explanation",
    "FaultClass",
    "FaultKind",
    "History",
    "HistoryError",
    "HistoryStep",
    "Limits",
    "MissionObservation",
    "Order",
    "PlanDiagnoser",
    "PlanModel",
    "PlanModelError",
    "StepResult",
    "Where",
    "alarm_decision",
    "build_model",
    "explain_history",
    "history_from_json",
    "load_history",
    "load_model",
    "render",
]
