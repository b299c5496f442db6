"""Experiments M2-M4 of MISSIONS.md as recorded histories on the test arena, explained right.

M2: a door closes behind the robot, found at the precondition check of the way back
(propagated): the region is the stretch since the door was seen open, the diagnosis "door1
closed between steps 3 and 13", an exogenous event. M3: a marker reported placed is not seen
later: the marking's fault mode explains it best (a local action fault). M4: opening a door
fails on a healthy robot: nothing explains it, a plan error, and the missing precondition is
(not (locked ?d)). Variants: the same failure with the arm broken is a component fault; a
critical alarm halts the step; a robot that did not arrive leaves the KB corrected to where
it most probably is.
"""

from __future__ import annotations

from dataclasses import replace

from host.atoms import Atom
from host.plandiag.history import (
    Alarm,
    ComponentHealth,
    HistoryStep,
    MissionObservation,
    StepResult,
    Where,
)
from host.plandiag.interpret import SymptomKind
from host.plandiag.model import PlanModel
from host.plandiag.pipeline import explain_history
from host.plandiag.result import FaultClass
from host.plandiag.text import render
from tests.plandiag.conftest import arena_history


def _labels(e: object) -> list[list[str]]:
    return [[c.fault.label() for c in h.faults] for h in e.histories]  # type: ignore[attr-defined]


def test_m2_a_door_closed_behind_the_robot(arena: PlanModel) -> None:
    for engine in ("sat", "tree"):
        e = explain_history(arena, arena_history("m2-door-closed"), engine)
        assert [s.kind for s in e.symptoms] == [SymptomKind.PROPAGATED]
        assert e.region is not None and not e.widened
        assert e.region.steps[0] == 3 and e.region.steps[-1] == 12  # since door1 was seen open
        assert e.region.expanded == ()  # no step's fault mode can close a door
        assert _labels(e) == [[f"door-closes(door1) before step {g}"] for g in range(4, 14)]
        assert e.classes() == [FaultClass.EVENT]
        assert e.outcome.complete and e.plan_error is None
        assert e.kb is not None and e.kb.observed == ("~open(door1)",) and not e.kb.changes()
        text = "\n".join(render(e))
        assert "door-closes(door1) between steps 3 and 13 (in one of 10 gaps)" in text
        assert ("without door-closes(door1) before step 4: step 13's precondition check "
                "contradicts the observations: it predicts open(door1)") in text


def test_m2_without_the_region_finds_the_same_and_expands_far_more(arena: PlanModel) -> None:
    h = arena_history("m2-door-closed")
    pruned = explain_history(arena, h, "tree")
    whole = explain_history(arena, h, "tree", use_region=False)
    assert _labels(whole) == _labels(pruned)
    assert whole.outcome.nodes > 20 * pruned.outcome.nodes


def test_m3_a_marker_reported_placed_is_missing(arena: PlanModel) -> None:
    for engine in ("sat", "tree"):
        e = explain_history(arena, arena_history("m3-marker-missing"), engine)
        assert [s.kind for s in e.symptoms] == [SymptomKind.LOCAL]
        best = e.histories[0]
        assert [c.fault.label() for c in best.faults] == [
            "mark-not-placed(tedusar,v1,room1) at step 5"]
        assert best.classes() == [FaultClass.ACTION]
        others = _labels(e)[1:]
        assert others == [[f"marker-lost(v1) before step {g}"] for g in range(6, 13)]
        assert best.probability > 0.7 and abs(sum(h.probability for h in e.histories) - 1) < 1e-9
        assert e.kb is not None and "~marked(v1)" in e.kb.observed  # so it is marked again


def test_m4_a_plan_error_names_the_missing_precondition(arena: PlanModel) -> None:
    for engine in ("sat", "tree", "naive"):
        e = explain_history(arena, arena_history("m4-plan-error"), engine)
        assert "open-door-fails" in e.suspicion.cleared  # layer 0: the arm works
        assert not e.histories and e.widened
        assert e.classes() == [FaultClass.PLAN_ERROR]
        pe = e.plan_error
        assert pe is not None and pe.step == 5 and pe.proven
        assert pe.conditions[0].literal == "(not (locked ?d))"
        assert pe.conditions[0].ground == "locked(door3)"
        assert pe.conditions[0].supported_by == (2,)  # door1 opened with locked false
        assert "class: plan error at step 5" in "\n".join(render(e))


def test_m4_with_the_arm_broken_is_a_component_fault(arena: PlanModel) -> None:
    h = arena_history("m4-plan-error")
    h = replace(h, components=ComponentHealth(h.components.healthy - {"arm"},
                                               frozenset({"arm"})))
    e = explain_history(arena, h)
    assert e.plan_error is None
    assert _labels(e) == [["open-door-fails(tedusar,door3,hall2,room3) at step 5"]]
    fault = e.histories[0].faults[0]
    assert fault.cls is FaultClass.COMPONENT and fault.broken == ("arm",)
    assert "layer 0: arm broken" in "\n".join(render(e))


def test_m4_without_layer_0_is_an_action_fault(arena: PlanModel) -> None:
    h = replace(arena_history("m4-plan-error"), components=ComponentHealth())
    e = explain_history(arena, h)
    assert e.classes() == [FaultClass.ACTION]
    assert _labels(e) == [["open-door-fails(tedusar,door3,hall2,room3) at step 5"]]


def test_a_critical_alarm_halts_the_step_and_debris_explains_it(arena: PlanModel) -> None:
    h = arena_history("m2-door-closed")
    steps = list(h.steps[:6])
    steps[5] = replace(steps[5], observations=())  # navigate(room1 -> hall2), bumped
    alarm = Alarm(6, Where.DURING, critical=True,
                  atoms=((Atom("blocked", ("room1", "hall2")), True),
                         (Atom("at", ("tedusar", "room1")), True)), message="bumper pressed")
    e = explain_history(arena, replace(h, steps=tuple(steps), alarm=alarm))
    assert e.context.problem.steps[5].nominal is not None
    assert not e.context.problem.steps[5].nominal.eff  # halted: its end effects never came
    assert [s.text for s in e.symptoms if s.atom is None] == [
        "step 6 navigate(tedusar,room1,hall2) was halted by a critical alarm"]
    assert {c.fault.op.name for h_ in e.histories for c in h_.faults} == {"debris-blocks"}
    assert e.histories[0].faults[0].fault.op.args == ("room1", "hall2")
    assert "(critical: the step was halted at once)" in render(e)[0]


def test_the_kb_is_corrected_to_where_the_robot_most_probably_is(arena: PlanModel) -> None:
    h = arena_history("m2-door-closed")
    # navigate hall1 -> hall2 reports success with no check; the next precondition check
    # finds the robot not in hall2
    steps = [h.steps[0],
             HistoryStep("navigate", ("tedusar", "hall1", "hall2")),
             HistoryStep("open-door", ("tedusar", "door2", "hall2", "room2"), StepResult.NOT_RUN,
                  (MissionObservation(Atom("at", ("tedusar", "hall2")), False, Where.PRE),))]
    e = explain_history(arena, replace(h, steps=tuple(steps), alarm=Alarm(3, Where.PRE)))
    assert _labels(e) == [["navigate-stuck(tedusar,hall1,hall2) at step 2"],
                          ["navigate-elsewhere(tedusar,hall1,hall2,start) at step 2"]]
    assert e.kb is not None
    assert e.kb.set_true == ("at(tedusar,hall1)",)  # stuck (0.05) beats elsewhere (0.02)
    assert e.kb.certain == ()  # the other history puts the robot at the start
    assert "at(tedusar,hall1) (probable)" in "\n".join(render(e))
