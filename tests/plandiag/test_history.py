"""The history's JSON form and its checks against the domain: every mistake names its place."""

from __future__ import annotations

import copy
import json
from pathlib import Path
from typing import Any

import pytest

from host.plandiag.errors import HistoryError
from host.plandiag.history import StepResult, Where, history_from_json, load_history
from host.plandiag.model import PlanModel
from host.plandiag.pipeline import explain_history
from tests.plandiag.conftest import ARENA

M2 = json.loads((ARENA / "m2-door-closed.json").read_text())


def test_a_history_survives_its_json_round_trip() -> None:
    h = history_from_json(M2)
    again = history_from_json(json.loads(json.dumps(h.to_json())))
    assert again == h
    assert h.steps[12].result is StepResult.NOT_RUN
    assert h.steps[12].observations[0].where is Where.PRE
    assert h.alarm is not None and h.alarm.step == 13 and not h.alarm.critical


def _edit(path: list[Any], value: Any) -> dict[str, Any]:
    data = copy.deepcopy(M2)
    target = data
    for key in path[:-1]:
        target = target[key]
    if value is KeyError:
        del target[path[-1]]
    else:
        target[path[-1]] = value
    return data


@pytest.mark.parametrize(("path", "value", "message"), [
    (["steps"], KeyError, r"steps: expected a list"),
    (["steps", 0, "result"], "done", r"steps\[0\].result: 'done' is not one of success, fail"),
    (["steps", 0, "observations", 0, "where"], "after",
     r"steps\[0\].observations\[0\].where: 'after' is not one of pre, during, post"),
    (["steps", 0, "observations", 0, "value"], "yes",
     r"steps\[0\].observations\[0\].value: 'yes' is not true or false"),
    (["steps", 0, "observations", 0, "atom"], "at(a,(b))",
     r"steps\[0\].observations\[0\].atom: .* is not an atom"),
    (["steps", 0, "start"], "noon", r"steps\[0\].start: 'noon' is not a time"),
    (["steps", 3], {"action": "detect-victim", "args": ["tedusar", "v1", "room1"],
                    "result": "not-run"}, r"steps\[3\] is not-run but later steps ran"),
    (["alarm", "step"], 14, r"alarm.step: 14 is not a step number \(.*1..13"),
    (["alarm", "critical"], "very", r"alarm.critical: 'very' is not true or false"),
    (["steps", 12, "observations", 0, "where"], "post",
     r"steps\[12\].observations: a not-run step has observations at post"),
])
def test_json_mistakes_name_the_place(path: list[Any], value: Any, message: str) -> None:
    with pytest.raises(HistoryError, match=message):
        history_from_json(_edit(path, value), "h.json")


@pytest.mark.parametrize(("path", "value", "message"), [
    (["steps", 0, "action"], "fly", r"steps\[0\]: unknown action 'fly'"),
    (["steps", 0, "args"], ["tedusar", "start"], r"steps\[0\].args: 2 arguments, the action "
                                                 r"takes 3"),
    (["steps", 0, "args"], ["tedusar", "start", "mars"], r"steps\[0\].args: unknown object 'mars'"),
    (["steps", 0, "args"], ["tedusar", "start", "door1"],
     r"steps\[0\].args: door1 is a door, \?to must be a place"),
    (["steps", 0, "observations", 0, "atom"], "at(tedusar)",
     r"steps\[0\].observations\[0\].atom: at\(tedusar\): takes 2 arguments"),
    (["steps", 0, "observations", 0, "atom"], "seen(tedusar)", r"unknown predicate"),
    (["init", 0], "at(tedusar,v1)", r"init: at\(tedusar,v1\): v1 is a victim, not a place"),
    (["objects", "door1"], "portal", r"objects.door1: unknown type 'portal'"),
    (["alarm", "where"], "during",
     r"the alarm is during step 13, which never ran"),
])
def test_a_history_that_does_not_fit_the_domain_names_the_place(
        arena: PlanModel, path: list[Any], value: Any, message: str) -> None:
    with pytest.raises(HistoryError, match=message):
        explain_history(arena, history_from_json(_edit(path, value)))


def test_an_alarm_at_a_precondition_check_of_a_step_that_ran_is_refused(
        arena: PlanModel) -> None:
    data = _edit(["alarm", "step"], 12)
    with pytest.raises(HistoryError, match=r"precondition check, but steps\[11\] ran"):
        explain_history(arena, history_from_json(data))


def test_contradicting_observations_at_one_moment_are_refused(arena: PlanModel) -> None:
    data = copy.deepcopy(M2)
    data["steps"][0]["observations"].append(
        {"atom": "at(tedusar,hall1)", "value": False, "where": "post"})
    with pytest.raises(HistoryError, match=r"observed both true and false at post"):
        explain_history(arena, history_from_json(data))


def test_unreadable_files_say_so(tmp_path: Path) -> None:
    with pytest.raises(HistoryError, match=r"cannot read the history"):
        load_history(tmp_path / "missing.json")
    bad = tmp_path / "bad.json"
    bad.write_text("{")
    with pytest.raises(HistoryError, match=r"bad.json: not JSON"):
        load_history(bad)
