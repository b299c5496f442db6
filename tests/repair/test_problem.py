"""Paper 000 §IV-E: I = O + AB(bad) + ~AB(good), G = ~AB(c) for every c."""

from __future__ import annotations

from pathlib import Path

import pytest
from pddl.parser.problem import ProblemParser

from host.diagnosis.logic import parse_literal
from host.diagnosis.model import Component, ComponentKind, SystemModel
from host.planning.domain import PddlAtom, load_domain
from host.planning.errors import ProblemError
from host.repair.planner import RepairPlanner
from host.repair.problem import build_problem, repair_model, to_pddl

from .conftest import TEDUSAR


def test_initial_state_and_goal_of_a_diagnosis(tedusar: RepairPlanner) -> None:
    p = build_problem(tedusar.model, {"jaguar"}, [parse_literal("~running(rviz)")])
    assert PddlAtom("ab", ("jaguar",)) in p.init
    assert [a for a in p.init if a.pred == "ab"] == [PddlAtom("ab", ("jaguar",))]
    assert PddlAtom("on", ("hokuyo",)) in p.init  # healthy device: on (clause 1)
    assert PddlAtom("on", ("jaguar",)) not in p.init  # bad device, unobserved: assumed off
    assert PddlAtom("running", ("jaguar_node",)) in p.init  # healthy node runs (clause 5)
    assert PddlAtom("running", ("rviz",)) not in p.init  # observed
    assert p.assumed == ("~on(jaguar)",)
    assert {a.args[0] for a in p.goal} == set(tedusar.model.types)


def test_observations_override_defaults_and_unrelated_ones_are_ignored(
    tedusar: RepairPlanner,
) -> None:
    obs = [parse_literal("on(jaguar)"), parse_literal("ok(/odom)")]
    p = build_problem(tedusar.model, {"jaguar"}, obs)
    assert PddlAtom("on", ("jaguar",)) in p.init
    assert p.assumed == ()
    assert p.ignored == ("ok(/odom)",)


def test_unknown_component_and_health_observation_are_user_errors(
    tedusar: RepairPlanner,
) -> None:
    with pytest.raises(ProblemError, match="nosuch"):
        build_problem(tedusar.model, {"nosuch"})
    with pytest.raises(ProblemError, match="health"):
        build_problem(tedusar.model, {"jaguar"}, [parse_literal("AB(jaguar)")])


def test_adapter_types_needs_and_protected_channel(tedusar: RepairPlanner) -> None:
    m = tedusar.model
    assert m.types["jaguar"] == "switchable"
    assert m.types["imu"] == "hardware"
    assert m.types["jaguar_node"] == "driver"
    assert m.types["hector_mapping"] == "node"
    assert m.needs["jaguar_node"] == ("jaguar",)
    assert m.needs["hector_mapping"] == ("hokuyo_node",)
    assert set(m.needs["rviz"]) == {"hector_mapping", "hokuyo_node"}
    assert m.protected == {"channel2"}  # the PC's channel
    assert m.types["channel2"] == "switchable"


def test_dependency_cycles_are_dropped_so_nodes_can_start() -> None:
    comps = {
        "a": Component("a", ComponentKind.N, subscribes=("/b",), publishes={"/a": ("/b",)}),
        "b": Component("b", ComponentKind.N, subscribes=("/a",), publishes={"/b": ("/a",)}),
        "c": Component("c", ComponentKind.N, subscribes=("/a",), publishes={"/c": ("/a",)}),
    }
    m = repair_model(SystemModel("cyc", Path("."), comps))
    assert m.needs == {"a": (), "b": (), "c": ("a",)}
    plan = RepairPlanner(load_domain(TEDUSAR), m).plan(
        {"a", "b", "c"}, [parse_literal(f"~running({n})") for n in comps])
    assert sorted(str(s) for s in plan.steps) == [
        "start_node(a)", "start_node(b)", "start_node(c)"]


def test_problem_pddl_parses_with_the_pddl_library(tedusar: RepairPlanner) -> None:
    text = to_pddl(build_problem(tedusar.model, {"jaguar", "hokuyo_node"}), "dxboard-repair")
    problem = ProblemParser()(text)
    assert {o.name for o in problem.objects} == set(tedusar.model.types)
    init = {str(f) for f in problem.init}
    assert "(ab jaguar)" in init and "(needs jaguar_node jaguar)" in init
    assert "(protected channel2)" in init
