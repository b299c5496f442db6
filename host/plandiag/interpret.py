"""The interpretation phase of paper 004 §4.3.1: alarm handler, sensor interpreter, symptoms.

- **Alarm handler.** ``alarm_decision`` is what the mission layer asks when a monitor raises
  an alarm while a step runs: a critical alarm halts the step at once, any other lets the step
  finish first. ``handle_alarm`` applies the same rule to a recorded history: the steps after
  the alarm are not part of the diagnosis, a step a critical alarm hit during its run is
  ``halted`` (its end effects never came), an alarm at a precondition check means the step
  never ran, and the alarm's atoms become observations at the alarm's moment.
- **Sensor interpreter.** Observations already are symbolic facts (atoms with values); what it
  adds is layer 0's diagnosis: a fault mode whose components were all shown working is out of
  suspicion, one with a broken component is suspected first (``context.Suspicion``).
- **Symptom identifier.** Every observation that contradicts what the dispatcher's knowledge
  base said at that moment is a symptom, as is every step that reported failure or was halted:
  **local** when it was found during a step or at its expected-state check, **propagated** when
  found at a precondition check (an earlier step or an event caused it).
"""

from __future__ import annotations

import logging
from dataclasses import dataclass, replace
from enum import StrEnum

from host.plandiag.context import Context, Suspicion
from host.plandiag.errors import HistoryError
from host.plandiag.history import (
    Alarm,
    ComponentHealth,
    History,
    MissionObservation,
    StepResult,
    Where,
)
from host.plandiag.model import FaultKind, PlanModel

log = logging.getLogger(__name__)


class Decision(StrEnum):
    HALT_NOW = "halt-now"
    FINISH_STEP = "finish-step"


def alarm_decision(alarm: Alarm) -> Decision:
    """What to do with the running step: critical alarms halt it at once."""
    return Decision.HALT_NOW if alarm.critical else Decision.FINISH_STEP


@dataclass(frozen=True)
class AlarmNote:
    """The alarm as the diagnosis sees it."""

    alarm: Alarm
    decision: Decision
    dropped_steps: int  # steps recorded after the alarm, left out
    synthesized: bool = False  # the history had no alarm: its last moment stands in


def handle_alarm(history: History) -> tuple[History, AlarmNote]:
    """The history up to the alarm, as the alarm left it."""
    if not history.steps:
        raise HistoryError("the history has no steps", "record at least the step that failed")
    alarm = history.alarm
    synthesized = alarm is None
    if alarm is None:
        last = history.steps[-1]
        alarm = Alarm(len(history.steps), Where.PRE if not last.executed() else Where.POST,
                      message="no alarm recorded: explaining the history up to its end")
    steps = list(history.steps[: alarm.step])
    dropped = len(history.steps) - len(steps)
    step = steps[-1]
    place = f"steps[{alarm.step - 1}]"
    if alarm.where is Where.PRE and step.executed():
        raise HistoryError(
            f"the alarm is at step {alarm.step}'s precondition check, but {place} ran "
            f"(result {step.result.value})",
            "a step whose precondition check failed is not-run; or move the alarm to 'during'")
    if alarm.where is not Where.PRE and not step.executed():
        raise HistoryError(f"the alarm is {alarm.where.value} step {alarm.step}, which never ran",
                           "put the alarm at its precondition check (where: pre)")
    decision = alarm_decision(alarm)
    if (alarm.where is Where.DURING and decision is Decision.HALT_NOW
            and step.result is StepResult.SUCCESS):
        step = replace(step, result=StepResult.HALTED)
    have = {(o.atom, o.where) for o in step.observations}
    extra = tuple(MissionObservation(a, v, alarm.where, alarm.time, "alarm")
                  for a, v in alarm.atoms if (a, alarm.where) not in have)
    steps[-1] = replace(step, observations=step.observations + extra)
    note = AlarmNote(alarm, decision, dropped, synthesized)
    if dropped:
        log.info("alarm at step %d: %d later step(s) left out", alarm.step, dropped)
    return replace(history, steps=tuple(steps), alarm=alarm), note


def sensor_interpreter(model: PlanModel, health: ComponentHealth) -> Suspicion:
    """Fault modes out of suspicion (all their components shown working) and confirmed (one
    of their components diagnosed broken), by layer 0's diagnosis."""
    cleared: dict[str, tuple[str, ...]] = {}
    confirmed: dict[str, tuple[str, ...]] = {}
    for fs in model.faults():
        if fs.kind is not FaultKind.MODE or not fs.components:
            continue
        broken = tuple(c for c in fs.components if c in health.broken)
        if broken:
            confirmed[fs.name] = broken
        elif all(c in health.healthy for c in fs.components):
            cleared[fs.name] = fs.components
    return Suspicion(cleared, confirmed)


class SymptomKind(StrEnum):
    LOCAL = "local"
    PROPAGATED = "propagated"


@dataclass(frozen=True)
class Symptom:
    kind: SymptomKind
    step: int
    where: Where
    point: int
    atom: int | None  # None: the step itself failed or was halted
    observed: bool = False
    text: str = ""


def identify_symptoms(ctx: Context, history: History) -> list[Symptom]:
    """Observations that contradict the dispatcher's knowledge base, and failed steps."""
    p = ctx.problem
    out: list[Symptom] = []
    for spec, step in zip(p.steps, history.steps, strict=False):
        i = spec.index
        for point in (2 * i - 1, 2 * i):
            for a, value, where in ctx.observed.get(point, ()):
                believed = bool((ctx.kb[point] >> a) & 1)
                if believed != value:
                    kind = SymptomKind.PROPAGATED if where == Where.PRE else SymptomKind.LOCAL
                    name = p.atom_name(a)
                    out.append(Symptom(kind, i, Where(where), point, a, value,
                                       f"{'' if value else '~'}{name} observed {where} step "
                                       f"{i}, the knowledge base said "
                                       f"{name if believed else '~' + name}"))
        if step.result is StepResult.FAIL:
            out.append(Symptom(SymptomKind.LOCAL, i, Where.DURING, 2 * i, None,
                               text=f"step {i} {spec.label} reported failure"))
        elif step.result is StepResult.HALTED:
            out.append(Symptom(SymptomKind.LOCAL, i, Where.DURING, 2 * i, None,
                               text=f"step {i} {spec.label} was halted by a critical alarm"))
        elif step.result is StepResult.SUCCESS and spec.nominal is None:
            out.append(Symptom(SymptomKind.LOCAL, i, Where.DURING, 2 * i, None,
                               text=f"step {i} {spec.label} reported success, but its static "
                               "precondition is false in the knowledge base"))
    return out
