"""The interpretation stages: alarm handler, sensor interpreter, symptoms, fault region."""

from __future__ import annotations

from dataclasses import replace

from host.atoms import Atom
from host.plandiag.context import BROKEN_PRIOR, interpret_context
from host.plandiag.history import Alarm, ComponentHealth, StepResult, Where
from host.plandiag.interpret import (
    Decision,
    SymptomKind,
    alarm_decision,
    handle_alarm,
    identify_symptoms,
    sensor_interpreter,
)
from host.plandiag.model import PlanModel
from host.plandiag.region import fault_region
from tests.plandiag.conftest import arena_history


def test_critical_alarms_halt_at_once_others_let_the_step_finish() -> None:
    assert alarm_decision(Alarm(1, Where.DURING, critical=True)) is Decision.HALT_NOW
    assert alarm_decision(Alarm(1, Where.DURING)) is Decision.FINISH_STEP
    h = arena_history("m3-marker-missing")
    halted, note = handle_alarm(replace(h, alarm=Alarm(4, Where.DURING, critical=True)))
    assert halted.steps[-1].result is StepResult.HALTED and note.dropped_steps == 8
    finished, _ = handle_alarm(replace(h, alarm=Alarm(4, Where.DURING)))
    assert finished.steps[-1].result is StepResult.SUCCESS and len(finished.steps) == 4


def test_the_alarm_atoms_become_observations_at_its_moment() -> None:
    h = arena_history("m3-marker-missing")
    alarm = Alarm(6, Where.DURING, atoms=((Atom("blocked", ("room1", "hall2")), True),))
    out, _ = handle_alarm(replace(h, alarm=alarm))
    extra = out.steps[-1].observations[-1]
    assert (extra.atom, extra.value, extra.where, extra.source) == (
        Atom("blocked", ("room1", "hall2")), True, Where.DURING, "alarm")


def test_a_history_without_an_alarm_is_explained_up_to_its_end() -> None:
    h = replace(arena_history("m2-door-closed"), alarm=None)
    out, note = handle_alarm(h)
    assert note.synthesized and note.alarm.step == 13 and note.alarm.where is Where.PRE
    assert out.alarm == note.alarm


def test_layer_0_clears_and_confirms_fault_modes(arena: PlanModel) -> None:
    health = ComponentHealth(frozenset({"jaguar", "jaguar_node", "arm"}),
                             frozenset({"hokuyo"}))
    s = sensor_interpreter(arena, health)
    assert set(s.cleared) == {"navigate-stuck", "pass-door-stuck", "open-door-fails"}
    assert dict(s.confirmed) == {"navigate-elsewhere": ("hokuyo",)}
    nav = {m.name: m for m in arena.modes["navigate"]}
    assert s.prior(nav["navigate-stuck"]) is None
    assert s.prior(nav["navigate-elsewhere"]) == BROKEN_PRIOR
    assert {m.name for m in arena.modes["mark-victim"]} == {"mark-not-placed"}
    assert s.prior(arena.modes["mark-victim"][0]) == 0.05  # marker_dispenser: no word


def test_symptoms_are_local_or_propagated_by_where_they_were_seen(arena: PlanModel) -> None:
    for name, kind, step in (("m2-door-closed", SymptomKind.PROPAGATED, 13),
                             ("m3-marker-missing", SymptomKind.LOCAL, 12),
                             ("m4-plan-error", SymptomKind.LOCAL, 5)):
        h, _ = handle_alarm(arena_history(name))
        ctx = interpret_context(arena, h, sensor_interpreter(arena, h.components))
        (sym,) = identify_symptoms(ctx, h)
        assert (sym.kind, sym.step) == (kind, step)


def test_the_kb_follows_the_dispatcher(arena: PlanModel) -> None:
    h, _ = handle_alarm(arena_history("m4-plan-error"))
    ctx = interpret_context(arena, h, sensor_interpreter(arena, h.components))
    p = ctx.problem
    door1 = p.task.index[("open", ("door1",))]
    assert not (ctx.kb[3] >> door1) & 1 and (ctx.kb[4] >> door1) & 1  # after open-door
    door3 = p.task.index[("open", ("door3",))]
    assert not (ctx.kb[10] >> door3) & 1  # open-door(door3) failed: no effect applied
    assert p.steps[4].nominal is None  # so it cannot have run as intended


def test_the_region_of_m2_is_the_door_closing_since_it_was_seen_open(arena: PlanModel) -> None:
    h, _ = handle_alarm(arena_history("m2-door-closed"))
    ctx = interpret_context(arena, h, sensor_interpreter(arena, h.components))
    region = fault_region(ctx, identify_symptoms(ctx, h))
    labels = sorted((ctx.problem.faults[f].at, ctx.problem.faults[f].action())
                    for f in region.suspects)
    assert labels == [(g, "door-closes(door1)") for g in range(3, 14)]
    assert region.steps == tuple(range(3, 13)) and region.expanded == ()
