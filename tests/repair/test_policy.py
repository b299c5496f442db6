"""Several diagnoses: repair all at once when cheap, else the most probable; say why."""

from __future__ import annotations

import pytest

from host.diagnosis.logic import parse_literal
from host.repair.errors import NoPlanError
from host.repair.planner import RepairPlanner
from host.repair.policy import Candidate, choose, prior_weight


def test_cheap_union_repairs_all_diagnoses_at_once(tedusar: RepairPlanner) -> None:
    # jaguar off, or its driver broken: power_up + restart covers both for the same price
    cands = [Candidate(frozenset({"jaguar"}), 0.6), Candidate(frozenset({"jaguar_node"}), 0.4)]
    choice = choose(tedusar, cands, [parse_literal("~on(jaguar)")])
    assert choice.strategy == "all-at-once"
    assert choice.bad == {"jaguar", "jaguar_node"}
    assert [str(s) for s in choice.plan.steps] == [
        "power_up(jaguar)", "stop_node(jaguar_node)", "start_node(jaguar_node)"]
    assert "at once" in choice.reason


def test_expensive_union_repairs_the_most_probable(tedusar: RepairPlanner) -> None:
    cands = [Candidate(frozenset({"jaguar"}), 0.2), Candidate(frozenset({"hokuyo"}), 0.8)]
    choice = choose(tedusar, cands)
    assert choice.strategy == "most-probable"
    assert choice.bad == {"hokuyo"}
    assert {s.args[0] for s in choice.plan.steps} == {"hokuyo", "hokuyo_node"}
    assert "p=0.80" in choice.reason and "would cost 6" in choice.reason


def test_unrepairable_candidate_is_skipped_and_recorded(tedusar: RepairPlanner) -> None:
    cands = [Candidate(frozenset({"imu"}), 0.7), Candidate(frozenset({"hokuyo"}), 0.3)]
    choice = choose(tedusar, cands)
    assert choice.bad == {"hokuyo"}
    assert "{imu} cannot be repaired" in choice.reason


def test_single_unrepairable_diagnosis_raises_its_own_reason(tedusar: RepairPlanner) -> None:
    with pytest.raises(NoPlanError, match="imu stays abnormal"):
        choose(tedusar, [Candidate(frozenset({"imu"}), 1.0)])


def test_empty_diagnosis_means_nothing_to_do(tedusar: RepairPlanner) -> None:
    choice = choose(tedusar, [Candidate(frozenset(), 0.9), Candidate(frozenset({"rviz"}), 0.1)])
    assert choice.strategy == "none" and len(choice.plan) == 0


def test_prior_weight_prefers_likelier_and_smaller_diagnoses() -> None:
    priors = {"a": 0.2, "b": 0.01}
    assert prior_weight({"a"}, priors) > prior_weight({"b"}, priors)
    assert prior_weight({"b"}, priors) > prior_weight({"a", "b"}, priors)
