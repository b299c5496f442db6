"""The layer contract (``host.layers``) and the mission's events (``host.events``): results
⟨s, Δ⟩ chained up the layers, and every mission event surviving the journal's JSON."""

from __future__ import annotations

import json

import pytest

from host.events import (
    ConditionCheck,
    Dispatch,
    KbChange,
    LayerResult,
    MissionState,
    MissionStep,
    TreeChange,
    describe,
    event_from_json,
)
from host.layers import EXECUTIVE, MISSION, SKILLS, Cause, Result


def test_a_failure_goes_up_with_the_explanation_of_every_layer_below() -> None:
    skill = Result.fail(SKILLS, "navigate stalled", ["hokuyo", "hokuyo"],
                        data={"place": "corridor"})
    tree = Result.fail(EXECUTIVE, "subtask navigate failed", below=skill)
    action = Result.fail(MISSION, "navigate(corridor, office) failed", below=tree)
    assert not action.success
    assert [c.layer for c in action.explanation] == [MISSION, EXECUTIVE, SKILLS]
    assert action.components() == ["hokuyo"]
    assert action.data == {"place": "corridor"}
    assert action.describe() == ("fail: mission: navigate(corridor, office) failed; because "
                                 "executive: subtask navigate failed; because skills: navigate "
                                 "stalled [hokuyo]")
    assert Result.from_json(json.loads(json.dumps(action.to_json()))) == action
    assert Result.ok({"x": 1}).describe() == "success"


EVENTS = [
    MissionState("m1", "planned", "", ("(searched office)",),
                 (MissionStep("navigate", ("entrance", "corridor", "door_entrance"), 0.0, 5.0),)),
    MissionState("m1", "stopped", "hokuyo is quarantined", components=("hokuyo",)),
    Dispatch("m1.1", "m1", 0, "navigate", ("corridor", "lab", "door_lab"),
             ("(at corridor)",), (ConditionCheck("(at corridor)", "start", True, True),
                                  ConditionCheck("(open door_lab)", "over all", True, False)),
             False, 12.5),
    TreeChange("m1.1", "navigate available", "RUNNING", "INVALID", 3, "holding: layer 0"),
    LayerResult(MISSION, "navigate", ("a", "b", "d"), False,
                (Cause(MISSION, "failed"), Cause(SKILLS, "stalled", ("hokuyo",))), 1.0, 2.5,
                "m1.1", ("(at a)",), {"place": "a"}),
    KbChange(("(at office)",), ("(at corridor)",), "sensing", "after navigate", "m1.1"),
]


@pytest.mark.parametrize("event", EVENTS, ids=lambda e: type(e).__name__)
def test_every_mission_event_round_trips_through_the_journal_json(event: object) -> None:
    text = json.dumps(event.to_json())  # type: ignore[attr-defined]
    assert event_from_json(event.kind, json.loads(text)) == event  # type: ignore[attr-defined]
    assert describe(event)  # type: ignore[arg-type]


def test_a_refused_dispatch_says_which_condition_did_not_hold() -> None:
    line = describe(EVENTS[2])  # type: ignore[arg-type]
    assert line == ("dispatch m1.1: navigate(corridor, lab, door_lab) refused: (open door_lab) "
                    "does not hold")
    assert "hokuyo" in describe(EVENTS[4])  # type: ignore[arg-type]
