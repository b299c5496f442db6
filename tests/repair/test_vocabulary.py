"""The planner reads the domain's own words: the original system's repair domain plans the
paper's repairs (issue 17, item 2), on our robot model and on the original's model files."""

from __future__ import annotations

import re
from pathlib import Path

import pytest
from pddl.parser.problem import ProblemParser

from host.diagnosis import generate, load_system, load_theory
from host.diagnosis.logic import parse_literal
from host.diagnosis.tug import write_tug
from host.planning.domain import load_domain, parse_domain_text
from host.planning.errors import DomainError, NoPlanError
from host.planning.plan import Plan
from host.planning.vocabulary import Vocabulary
from host.repair.planner import RepairPlanner
from host.repair.problem import RepairModel, repair_model
from host.repair.theory_model import repair_model_of
from tests.diagnosis.originals import DOMAIN, JAGUAR_2012

from .conftest import TEDUSAR


@pytest.fixture(scope="module")
def original() -> RepairPlanner:
    """The TEDUSAR robot with the original system's repair domain."""
    return RepairPlanner.for_system(TEDUSAR, DOMAIN)


def steps(plan: Plan) -> list[str]:
    return [str(s) for s in plan.steps]


def tedusar_model() -> RepairModel:
    return repair_model(load_system(TEDUSAR))


def test_vocabularies_are_inferred() -> None:
    ours = load_domain(TEDUSAR).vocabulary
    assert (ours.abnormal, ours.healthy, ours.powered, ours.running) == (
        "ab", None, "on", "running")
    assert ours.complements == {} and ours.goal() == ("ab", False)
    theirs = load_domain(DOMAIN).vocabulary
    assert (theirs.abnormal, theirs.healthy, theirs.powered, theirs.running) == (
        "bad", "good", "on", "running")
    assert theirs.complements["on"] == "not_on" and theirs.complements["running"] == \
        "not_running"
    assert theirs.goal() == ("good", True)


def test_the_original_domain_power_cycles_a_hung_lidar(original: RepairPlanner) -> None:
    plan = original.plan({"hokuyo"}, [parse_literal("on(hokuyo)")])
    assert steps(plan) == ["shutdown(hokuyo)", "power_up(hokuyo)"]


def test_the_original_domain_plans_the_device_shut_down(original: RepairPlanner) -> None:
    # paper 000 §VI-B: the base lost power and its driver its device
    obs = [parse_literal("~on(jaguar)"), parse_literal("running(jaguar_node)")]
    plan = original.plan({"jaguar", "jaguar_node"}, obs)
    assert steps(plan) == ["power_up(jaguar)", "stop_node(jaguar_node)",
                           "start_node(jaguar_node)"]


def test_the_original_domain_plans_the_power_up(original: RepairPlanner) -> None:
    devices = ["jaguar", "hokuyo", "laser_alignment"]
    nodes = ["jaguar_node", "hokuyo_node", "laser_alignment_node", "imu_node", "joy_node",
             "jaguar_teleop_node", "hector_mapping", "laser_alignment_control"]
    obs = [parse_literal(f"~on({d})") for d in devices]
    obs += [parse_literal(f"~running({n})") for n in nodes]
    plan = original.plan(devices + nodes, obs)
    assert sorted(steps(plan)) == sorted([f"power_up({d})" for d in devices]
                                         + [f"start_node({n})" for n in nodes])


def test_the_problem_in_the_originals_words(original: RepairPlanner) -> None:
    p = original.problem({"hokuyo"}, [parse_literal("on(hokuyo)"),
                                      parse_literal("~running(rviz)")])
    init = {str(a) for a in p.init}
    assert {"bad(hokuyo)", "on(hokuyo)", "good(jaguar)", "not_running(rviz)"} <= init
    assert "good(hokuyo)" not in init and "ab(hokuyo)" not in init
    assert p.goal_holds and {a.pred for a in p.goal} == {"good"}
    text = original.problem_pddl(p)
    assert "(good hokuyo)" in text and "(not (good" not in text
    types = {str(o.name): {str(t) for t in o.type_tags} for o in ProblemParser()(text).objects}
    assert types["jaguar_node"] == {"node"} and types["jaguar"] == {"hardware"}  # driver, SH


def test_protection_in_the_originals_words(original: RepairPlanner) -> None:
    # the PC's protected channel: the original's shutdown makes not_on true, never on false
    assert any("shutdown(channel2)" in label for label, _ in original.task.removed)
    with pytest.raises(NoPlanError):
        original.plan({"channel2"}, [parse_literal("on(channel2)")])


def test_a_declared_vocabulary(tmp_path: Path) -> None:
    text = """; dxboard-vocabulary: abnormal=broken powered=powered running=alive
(define (domain other)
  (:requirements :strips :negative-preconditions)
  (:predicates (broken ?c) (powered ?c) (alive ?c))
  (:action replug :parameters (?c) :precondition (and (broken ?c) (powered ?c))
    :effect (not (broken ?c)))
  (:action wake :parameters (?c)
    :precondition (and (broken ?c) (not (alive ?c)) (not (powered ?c)))
    :effect (and (alive ?c) (not (broken ?c)))))"""
    domain = parse_domain_text(text, tmp_path / "d.pddl")
    assert domain.vocabulary.declared == ("abnormal", "powered", "running")
    planner = RepairPlanner(domain, tedusar_model())
    assert steps(planner.plan({"hokuyo"}, [parse_literal("on(hokuyo)")])) == ["replug(hokuyo)"]
    assert steps(planner.plan({"hokuyo_node"}, [parse_literal("~running(hokuyo_node)")])) == [
        "wake(hokuyo_node)"]


@pytest.mark.parametrize(("line", "needle"), [
    ("; dxboard-vocabulary: abnormal=nosuch", "declares no predicate (nosuch ?x)"),
    ("; dxboard-vocabulary: sick=ab", "cannot read 'sick=ab'"),
])
def test_a_bad_declaration_is_refused(line: str, needle: str) -> None:
    text = line + "\n" + (TEDUSAR / "repair.pddl").read_text()
    with pytest.raises(DomainError, match=re.escape(needle)):
        parse_domain_text(text)


def test_a_domain_without_health_words_cannot_plan_repairs() -> None:
    text = """(define (domain gripper) (:requirements :strips)
      (:predicates (room ?r) (at-robby ?r))
      (:action move :parameters (?from ?to) :precondition (and (room ?from) (at-robby ?from))
        :effect (and (at-robby ?to) (not (at-robby ?from)))))"""
    domain = parse_domain_text(text)
    assert domain.vocabulary == Vocabulary(None, None, None, None, {})
    with pytest.raises(DomainError, match="dxboard-vocabulary: abnormal=PRED"):
        RepairPlanner(domain, tedusar_model())


def test_a_tug_model_gives_the_robot_models_kinds_and_dependencies(tmp_path: Path) -> None:
    system = load_system(TEDUSAR)
    f = tmp_path / "tedusar.yaml"
    write_tug(generate(system), f)
    from_yaml = repair_model(system)
    from_tug = repair_model_of(load_theory(f), "tedusar")
    for name, typ in from_tug.types.items():
        assert typ == from_yaml.types[name], name
    for node, needs in from_tug.needs.items():
        if node != "rviz":  # reads topics but publishes none: the clauses do not say what
            assert set(needs) == set(from_yaml.needs[node]), node


def test_the_original_model_file_and_domain_plan_the_lidar(tmp_path: Path) -> None:
    planner = RepairPlanner.for_system(JAGUAR_2012, DOMAIN)
    assert planner.model.types["hokuyo"] == "switchable"
    assert planner.model.types["hokuyo_node"] == "driver"
    assert planner.model.needs["hokuyo_node"] == ("hokuyo",)
    plan = planner.plan({"hokuyo", "hokuyo_node"},
                        [parse_literal("on(hokuyo)"), parse_literal("running(hokuyo_node)")])
    assert sorted(steps(plan)) == ["power_up(hokuyo)", "shutdown(hokuyo)",
                                   "start_node(hokuyo_node)", "stop_node(hokuyo_node)"]
