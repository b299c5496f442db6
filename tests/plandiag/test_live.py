"""The mission layer's plan-execution diagnosis without a world: the temporal domain read as
STRIPS, and the history the diagnoser records from the dispatcher's events and sensing — where
each observation goes (static atoms to the initial KB, an atom the step's action names to its
expected-state check, any other to the next step's precondition check) and where the alarm is."""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

from host.atoms import Atom
from host.events import ConditionCheck, Dispatch, KbChange
from host.layers import MISSION, Result
from host.mission.dispatcher import Dispatched, DispatchOutcome
from host.mission.files import load_mission
from host.plandiag.history import Alarm, HistoryStep, MissionObservation, StepResult, Where
from host.plandiag.live import MissionDiagnoser, corrections
from host.plandiag.model import PlanModel
from host.plandiag.pipeline import explain_history
from host.plandiag.strips import load_mission_model, step_of, strips_text
from tests.plandiag.conftest import arena_history

TEDUSAR = Path(__file__).resolve().parents[2] / "models" / "tedusar"
FILES = load_mission(TEDUSAR)
KB = ("(at office)", "(connects door_office corridor office)",
      "(connects door_office office corridor)", "(level)", "(open door_office)")


def test_a_durative_action_is_one_step_with_its_conditions_and_effects() -> None:
    pre, eff = step_of(FILES.domain.actions["navigate"])
    assert (("open", "?d"), True) in pre and (("level",), True) in pre  # over all, at start
    assert eff == [(("at", "?from"), False), (("at", "?to"), True)]
    text = strips_text(FILES.domain)
    assert "(:action navigate" in text and ":durative" not in text


def test_the_mission_model_has_the_fault_modes_and_events_of_faults_pddl() -> None:
    m = load_mission_model(FILES.domain, FILES.path.parent)
    assert [f.name for f in m.modes["mark_victim"]] == ["mark-not-placed"]
    assert {e.name for e in m.events} == {"door-closes", "marker-lost"}
    assert {"connects", "victim-in", "seen", "locked"} <= set(m.domain.statics)


def dispatch(n: int, action: str, args: tuple[str, ...], ok: bool = True,
             failed: tuple[ConditionCheck, ...] = ()) -> Dispatch:
    return Dispatch(f"m1.{n}", "m1", n, action, args, KB, failed, ok, float(n))


def test_observations_go_where_the_diagnosis_can_use_them() -> None:
    d = MissionDiagnoser(load_mission_model(FILES.domain, FILES.path.parent), FILES.domain, "m1")
    d.on_event(dispatch(1, "search_room", ("office",)))
    d.sensed([(("victim-in", "victim_1", "office"), True), (("open", "door_office"), False),
              (("at", "office"), True)], "m1.1")
    d.ended(Dispatched(DispatchOutcome.DONE, Result.ok(), "m1.1"), 1.5)
    check = ConditionCheck("(open door_office)", "over all", True, False)
    d.on_event(dispatch(2, "navigate", ("office", "corridor", "door_office"), False, (check,)))
    d.ended(Dispatched(DispatchOutcome.REFUSED, Result.fail(MISSION, "refused"), "m1.2"), 2.0)
    h = d.history({"office": "room", "corridor": "room", "door_office": "door",
                   "victim_1": "victim"}, "refused")
    assert "victim-in(victim_1,office)" in {str(a) for a in h.init}  # static: held all along
    first, second = h.steps
    assert [(o.literal(), o.where) for o in first.observations] == [("at(office)", Where.POST)]
    assert second.result is StepResult.NOT_RUN
    assert [(o.literal(), o.where) for o in second.observations] == [
        ("~open(door_office)", Where.PRE)]  # seen after step 1: how the world was before 2
    assert h.alarm is not None and (h.alarm.step, h.alarm.where) == (2, Where.PRE)
    assert [(str(a), v) for a, v in h.alarm.atoms] == [("open(door_office)", False)]
    e = d.diagnose(h.objects, "refused")
    assert e is not None and e.event.classes == ["exogenous event"]
    assert e.event.symptoms[0].startswith("propagated: ~open(door_office) observed pre step 2")


def test_a_refused_check_is_an_observation_of_what_the_kb_held() -> None:
    d = MissionDiagnoser(load_mission_model(FILES.domain, FILES.path.parent), FILES.domain, "m1")
    check = ConditionCheck("(level)", "start", True, False)
    d.on_event(dispatch(1, "navigate", ("office", "corridor", "door_office"), False, (check,)))
    h = d.history({"office": "room", "corridor": "room", "door_office": "door"}, "refused")
    assert [(o.literal(), o.where) for o in h.steps[0].observations] == [("~level", Where.PRE)]


def test_sensing_that_takes_back_an_effect_is_a_surprise_once() -> None:
    d = MissionDiagnoser(load_mission_model(FILES.domain, FILES.path.parent), FILES.domain, "m1")
    d.on_event(KbChange(("(marked victim_1)",), (), "effect", "end of mark_victim"))
    d.on_event(KbChange((), ("(open door_office)",), "sensing"))  # never an effect: no surprise
    assert d.surprise() == ()
    d.on_event(KbChange((), ("(marked victim_1)",), "sensing"))
    assert d.surprise() == ((("marked", "victim_1"), True),)
    assert d.surprise() == ()


def test_the_corrections_are_what_the_most_probable_history_implies_beyond_sensing(
        arena: PlanModel) -> None:
    h = arena_history("m2-door-closed")
    steps = [h.steps[0], HistoryStep("navigate", ("tedusar", "hall1", "hall2")),
             HistoryStep("open-door", ("tedusar", "door2", "hall2", "room2"), StepResult.NOT_RUN,
                  (MissionObservation(Atom("at", ("tedusar", "hall2")), False, Where.PRE),))]
    e = explain_history(arena, replace(h, steps=tuple(steps), alarm=Alarm(3, Where.PRE)))
    # navigate-stuck is the most probable: the robot is still in hall1, which nobody observed
    assert corrections(e) == ((("at", "tedusar", "hall1"), True),)
