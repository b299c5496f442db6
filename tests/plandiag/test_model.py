"""Reading a mission domain with its annotated fault modes and events (model.py, annotate.py)."""

from __future__ import annotations

from pathlib import Path

import pytest

from host.plandiag.errors import PlanModelError
from host.plandiag.model import FaultKind, PlanModel, build_model, load_model
from tests.plandiag.conftest import ARENA

MISSION = (ARENA / "mission.pddl").read_text()
HEAD = "(define (domain f)\n  (:requirements :strips :typing :negative-preconditions)\n"
STUCK = """  (:action navigate-stuck
    :parameters (?r - robot ?from - place ?to - place)
    :precondition (at ?r ?from) :effect (and))
"""


def _faults(body: str) -> str:
    return HEAD + body + ")\n"


def test_the_arena_has_its_modes_and_events(arena: PlanModel) -> None:
    assert sorted(arena.actions) == ["detect-victim", "mark-victim", "navigate", "open-door",
                                     "pass-door"]
    nav = {m.name: m for m in arena.modes["navigate"]}
    assert nav["navigate-stuck"].prior == 0.05
    assert nav["navigate-stuck"].components == ("jaguar", "jaguar_node")
    assert nav["navigate-elsewhere"].schema.parameters[3] == ("?actual", "place")
    assert {e.name for e in arena.events} == {"door-closes", "debris-blocks", "victim-moves",
                                              "marker-lost"}
    assert all(e.kind is FaultKind.EVENT for e in arena.events)
    # only an event changes `blocked`: in the diagnosis model it is a fluent, `locked` static
    assert "blocked" in arena.domain.fluents and "locked" in arena.domain.statics


def test_a_domain_without_faults_has_none(tmp_path: Path) -> None:
    (tmp_path / "mission.pddl").write_text(MISSION)
    m = load_model(tmp_path)
    assert m.faults() == [] and m.faults_path is None


def test_faults_may_declare_their_own_vocabulary_when_it_agrees() -> None:
    own = (HEAD + "  (:types robot place door victim)\n"
           "  (:predicates (at ?r - robot ?p - place))\n"
           "  ; @mode navigate prior=0.1\n" + STUCK + ")\n")
    assert [m.name for m in build_model(MISSION, own).modes["navigate"]] == ["navigate-stuck"]
    wrong = own.replace("(at ?r - robot ?p - place)", "(at ?r - robot)")
    with pytest.raises(PlanModelError, match=r"predicate at/1 is not in the mission domain"):
        build_model(MISSION, wrong)


@pytest.mark.parametrize(("body", "message"), [
    (STUCK, r"faults.pddl:3: action navigate-stuck has no annotation"),
    ("  ; @mode navigate\n" + STUCK, r"faults.pddl:3: the annotation has no prior"),
    ("  ; @mode navigate prior=1.5\n" + STUCK, r"prior=1.5 is not a probability"),
    ("  ; @mode navigate prior=high\n" + STUCK, r"prior=high is not a probability"),
    ("  ; @mode prior=0.1\n" + STUCK, r"@mode needs the action it is a mode of"),
    ("  ; @mode navigate prior=0.1 color=red\n" + STUCK, r"'color=red' is not prior=P"),
    ("  ; @fault navigate prior=0.1\n" + STUCK, r"unknown annotation @fault"),
    ("  ; @mode fly prior=0.1\n" + STUCK, r"@mode names 'fly', which the mission domain lacks"),
    ("  ; @event prior=0.1\n", r"faults.pddl:3: the annotation is not followed by an action"),
    ("  ; @event prior=0.1\n  ; @event prior=0.2\n" + STUCK.replace("stuck", "x"),
     r"faults.pddl:3: the annotation is not followed by an action"),
    ("  ; @mode navigate prior=0.1\n" + STUCK.replace("?from - place", "?from - door"),
     r"first parameters have the types \(robot door place\), navigate's are "
     r"\(robot place place\)"),
    ("  ; @mode navigate prior=0.1\n" + STUCK.replace("navigate-stuck", "navigate"),
     r"the name is already a mission action"),
    ("  ; @event prior=0.1\n  (:action e :parameters (?d - door) :precondition (open ?d)\n"
     "    :effect (when (open ?d) (not (open ?d))))\n",
     r"has a conditional effect \(when\)"),
    ("  ; @event prior=0.1\n  (:action e :parameters (?d - door) :effect (shut ?d))\n",
     r"faults.pddl: not a valid PDDL domain"),
])
def test_mistakes_in_faults_pddl_name_the_place(body: str, message: str) -> None:
    with pytest.raises(PlanModelError, match=message) as info:
        build_model(MISSION, _faults(body), faults_path=Path("faults.pddl"))
    assert info.value.hint  # and say what to do


def test_a_missing_mission_domain_says_where_to_put_it(tmp_path: Path) -> None:
    with pytest.raises(PlanModelError, match=r"mission.pddl: cannot read the mission domain"):
        load_model(tmp_path)


def test_line_numbers_survive_the_borrowed_sections() -> None:
    body = "  ; @mode navigate prior=0.1\n" + STUCK.replace("(and))", "(and)) oops")
    with pytest.raises(PlanModelError, match=r"not a valid PDDL domain: .*'oops'\) at line 6,"):
        build_model(MISSION, _faults(body))  # the types and predicates went in on line 4
