"""Plan-execution diagnosis inside the running mission (issue 16): a door closes behind the
robot in the real arena; the way back is refused at its precondition check, the diagnosis
explains it as an exogenous event in the stretch since the door was last seen open, the
knowledge base is corrected, and the mission replans from it and completes."""

from __future__ import annotations

import asyncio

from host.events import DiagnosisRecord, Dispatch, KbChange, MissionState, PlanDiagnosis
from tests.mission.harness import Harness, until


async def test_a_door_closed_behind_the_robot_is_diagnosed_and_planned_around(
        h: Harness) -> None:
    mission = asyncio.ensure_future(h.runner().run())

    def marking() -> bool:
        return h.world.arena.place() == "office" and any(
            d.action == "mark_victim" and d.args == ("victim_1", "office")
            for d in h.of(Dispatch))

    await until(marking, "the robot marking the victim in the office", 120)
    assert h.world.arena.set_door("door_office", False) == ""  # it falls shut behind it
    outcome = await asyncio.wait_for(mission, 240)
    assert outcome.completed, outcome.detail
    refused = [d for d in h.of(Dispatch) if not d.ok]
    assert [(d.action, d.args) for d in refused] == [
        ("navigate", ("office", "corridor", "door_office"))]
    diag, = h.of(PlanDiagnosis)
    assert diag.dispatch_id == refused[0].dispatch_id
    assert diag.classes == ["exogenous event"]
    assert diag.symptoms and diag.symptoms[0].startswith("propagated: ~open(door_office)")
    assert "door-closes(door_office)" in diag.histories[0]
    assert diag.region.startswith("fault region:")
    assert any("door-closes(door_office) happened: ~open(door_office)" in line
               for line in diag.path)
    assert "~open(door_office) (observed)" in diag.kb
    # the plan after the diagnosis opens the door from inside and drives out through it
    after = [e for e in h.of(MissionState) if e.state == "planned"]
    i = next(n for n, e in enumerate(h.events) if isinstance(e, PlanDiagnosis))
    new = next(e for e in h.events[i:] if isinstance(e, MissionState) and e.state == "planned")
    assert new in after
    assert [str(s) for s in new.plan[:2]] == ["open_door(door_office, office, corridor)",
                                               "navigate(office, corridor, door_office)"]
    assert h.world.arena.doors()["door_office"]  # opened again by the robot
    assert not [e for e in h.of(KbChange) if e.source == "diagnosis"]  # nothing unobserved


async def test_a_marker_reported_placed_but_missing_is_an_action_fault_and_marked_again(
        h: Harness) -> None:
    h.world.arena.jammed = True  # the dispenser: the next mark reports a marker it did not leave
    outcome = await asyncio.wait_for(h.runner().run(), 240)
    assert outcome.completed, outcome.detail
    marks = [d for d in h.of(Dispatch) if d.action == "mark_victim"]
    victim = marks[0].args[0]
    diag, = h.of(PlanDiagnosis)
    assert diag.dispatch_id == marks[0].dispatch_id
    assert diag.classes == ["action fault"]
    assert f"reported success but the world shows not (marked {victim})" in diag.alarm
    assert diag.symptoms[0].startswith(f"local: ~marked({victim}) observed post step")
    assert f"mark-not-placed({victim},{marks[0].args[1]}) at step" in diag.histories[0]
    assert f"~marked({victim}) (observed)" in diag.kb
    assert [d.args[0] for d in marks].count(victim) == 2  # marked again
    assert sorted(h.world.arena.marked) == ["victim_1", "victim_2"]


async def test_a_locked_door_on_a_healthy_robot_is_a_plan_error_naming_the_condition(
        h: Harness) -> None:
    h.say(DiagnosisRecord(((),)))  # layer 0: every component healthy
    assert h.world.arena.set_door("door_office", False) == ""  # the robot opens this one
    assert h.world.arena.set_lock("door_lab", True) == ""  # and fails at this one
    outcome = await asyncio.wait_for(h.runner().run(), 240)
    assert not outcome.completed and "(searched lab)" in outcome.detail
    diag, = h.of(PlanDiagnosis)
    assert diag.classes == ["plan error"] and not diag.histories
    assert "open_door(door_lab,corridor,lab)" in diag.plan_error
    assert "reported failure; no fault mode or event explains it" in diag.plan_error
    assert diag.plan_error.split("; the domain may lack ")[1].startswith(
        "(not (locked ?d)) (locked(door_lab))")
    locks = {a for d in h.of(Dispatch) for a in d.kb if a.startswith("(locked")}
    assert locks == {"(locked door_lab)"}  # sensed from the world
    opened = [d for d in h.of(Dispatch) if d.action == "open_door"]
    assert [(d.args[0], d.ok) for d in opened] == [("door_office", True), ("door_lab", True)]
