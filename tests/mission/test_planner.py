"""Layer 3's temporal PDDL (``host.planning.temporal_pddl``) and planner
(``host.planning.temporal_planner``): durative actions with start / over-all / end conditions
and effects, read with the place of every mistake; an optimal schedule; plans around actions a
layer below took away."""

from __future__ import annotations

from pathlib import Path

import pytest

from host.planning.temporal_pddl import PddlError, load, parse_domain, parse_problem
from host.planning.temporal_planner import applicable, ground, plan

TEDUSAR = Path(__file__).resolve().parents[2] / "models" / "tedusar" / "mission"

DOMAIN = """(define (domain d)
  (:requirements :strips :typing :durative-actions :negative-preconditions)
  (:types room door)
  (:predicates (at ?r - room) (open ?d - door) (link ?d - door ?a - room ?b - room))
  (:durative-action go
    :parameters (?a - room ?b - room ?d - door)
    :duration (= ?duration 4)
    :condition (and (at start (at ?a)) (at start (link ?d ?a ?b)) (over all (open ?d)))
    :effect (and (at start (not (at ?a))) (at end (at ?b))))
  (:durative-action open
    :parameters (?d - door ?a - room ?b - room)
    :duration (= ?duration 1)
    :condition (and (over all (at ?a)) (at start (link ?d ?a ?b)) (at start (not (open ?d))))
    :effect (and (at end (open ?d))))
  (:action teleport :parameters (?a - room ?b - room)
    :precondition (and (at ?a)) :effect (and (not (at ?a)) (at ?b))))
"""
PROBLEM = """(define (problem p) (:domain d)
  (:objects x y - room dx - door)
  (:init (at x) (link dx x y) (link dx y x))
  (:goal (and (at y))))
"""


def test_durative_actions_are_read_with_their_timed_conditions_and_effects() -> None:
    dom = parse_domain(DOMAIN)
    go = dom.actions["go"]
    assert go.duration == 4.0
    assert go.cond["start"] == ((("at", "?a"), True), (("link", "?d", "?a", "?b"), True))
    assert go.cond["over all"] == ((("open", "?d"), True),)
    assert go.eff["start"] == ((("at", "?a"), False),)
    assert go.eff["end"] == ((("at", "?b"), True),)
    tp = dom.actions["teleport"]  # an instantaneous action: duration 0, start -> end
    assert tp.duration == 0.0 and tp.cond["start"] and tp.eff["end"]


def test_the_plan_opens_the_door_that_must_stay_open_over_all_of_the_drive() -> None:
    dom = parse_domain(DOMAIN.replace("(:action teleport", "(:action noop").replace(
        "(and (at ?a)) :effect (and (not (at ?a)) (at ?b))", "(and (at ?a)) :effect (and)"))
    prob = parse_problem(PROBLEM, dom)
    steps = plan(ground(dom, prob), prob.init, prob.goal)
    assert steps is not None
    assert [str(s.ground) for s in steps] == ["open(dx, x, y)", "go(x, y, dx)"]
    assert [s.start for s in steps] == [0.0, 1.0] and steps[-1].end == 5.0
    go = steps[1].ground
    assert applicable(prob.init, go) is None  # over all (open dx) fails while it is closed


def test_the_cheapest_schedule_is_chosen_and_a_taken_away_action_is_planned_around() -> None:
    dom = parse_domain(DOMAIN)
    prob = parse_problem(PROBLEM, dom)
    acts = ground(dom, prob)
    steps = plan(acts, prob.init, prob.goal)
    assert steps is not None and [s.ground.name for s in steps] == ["teleport"]  # 0 s
    steps = plan(acts, prob.init, prob.goal, allowed=lambda g: g.name != "teleport")
    assert steps is not None and [s.ground.name for s in steps] == ["open", "go"]
    assert plan(acts, prob.init, prob.goal, allowed=lambda g: g.name == "open") is None


def test_the_tedusar_mission_plans_around_the_closed_lab_door() -> None:
    dom, prob = load(TEDUSAR / "domain.pddl", TEDUSAR / "problem.pddl")
    state = prob.init - {("open", "door_lab")}  # as the world shows it
    steps = plan(ground(dom, prob), state, prob.goal)
    assert steps is not None
    names = [str(s.ground) for s in steps]
    assert names[0] == "level_laser()"
    assert names.index("open_door(door_lab, corridor, lab)") < names.index(
        "navigate(corridor, lab, door_lab)")
    assert {"search_room(office)", "search_room(lab)", "search_room(storage)"} <= set(names)


@pytest.mark.parametrize(("text", "where"), [
    (DOMAIN.replace("(over all (open ?d))", "(sometime (open ?d))"), "domain.pddl:8"),
    (DOMAIN.replace(":duration (= ?duration 4)", ":duration (<= ?duration 4)"), "go: give"),
    (DOMAIN.replace("(at end (at ?b))", "(at end (at ?c))"), "?c is not a parameter"),
    (DOMAIN.replace(":durative-actions", ":fluents"), ":fluents is not supported"),
    (DOMAIN.replace("(open ?d - door)", ""), "predicate open is not declared"),
    (DOMAIN[:-3], "is never closed"),
])
def test_a_domain_outside_the_subset_is_refused_naming_the_place(text: str, where: str) -> None:
    with pytest.raises(PddlError) as err:
        parse_domain(text)
    assert where in str(err.value)


def test_a_problem_naming_an_unknown_object_is_refused() -> None:
    dom = parse_domain(DOMAIN)
    with pytest.raises(PddlError, match="z is not an object"):
        parse_problem(PROBLEM.replace("(at y)", "(at z)"), dom)


def test_the_pddl_library_of_the_repair_planner_cannot_read_the_temporal_domain() -> None:
    """Why the mission layer has its own reader: ``pddl`` stops at ``:durative-actions``."""
    import pddl

    with pytest.raises(Exception, match="durative-actions"):
        pddl.parse_domain(TEDUSAR / "domain.pddl")
