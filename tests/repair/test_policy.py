"""Several diagnoses: repair all at once when cheap, else the most probable; say why."""

from __future__ import annotations

import pytest

from host.diagnosis import Clause, Diagnoser, Literal, Theory, ab
from host.diagnosis.logic import parse_literal
from host.planning.errors import NoPlanError
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


def _two_conflicts(priors: dict[str, float]) -> Theory:
    """Conflicts {jaguar, hokuyo} and {jaguar, hokuyo_node}: the minimal diagnoses are
    {jaguar} and {hokuyo, hokuyo_node} (the issue 17 example in the robot's names)."""
    def rule(x: str, out: str) -> Clause:
        return Clause((Literal(ab("jaguar")), Literal(ab(x)), Literal(f"ok({out})")))

    return Theory(("hokuyo", "hokuyo_node", "jaguar"), (rule("hokuyo", "x"),
                                                       rule("hokuyo_node", "y")), priors)


@pytest.mark.parametrize(("priors", "first"), [
    # the pair is 1000x likelier than the single component: most probable, not smallest
    ({"hokuyo": 0.5, "hokuyo_node": 0.5, "jaguar": 0.001}, {"hokuyo", "hokuyo_node"}),
    # the single one is likelier
    ({"hokuyo": 0.01, "hokuyo_node": 0.01, "jaguar": 0.2}, {"jaguar"}),
    # an exact tie of the priors (odds 1/81 = (1/9)^2): the smaller diagnosis, as listed
    ({"hokuyo": 0.1, "hokuyo_node": 0.1, "jaguar": 1 / 82}, {"jaguar"}),
])
def test_the_daemon_repairs_the_diagnosers_first(tedusar: RepairPlanner, priors: dict[str, float],
                                                 first: set[str]) -> None:
    """Item 3 of issue 17: the daemon's candidates (built as host/daemon/repairs.py does) from
    the diagnoser's result, most probable first, and the policy repairs that first one."""
    with Diagnoser(_two_conflicts(priors)) as d:
        d.observe("~ok(x)")
        d.observe("~ok(y)")
        result = d.diagnose()
    assert result.bad_sets()[0] == first
    cands = [Candidate(frozenset(x.bad), x.probability) for x in result.diagnoses]
    for order in (cands, cands[::-1]):
        choice = choose(tedusar, order)
        assert choice.strategy == "most-probable"
        assert choice.bad == first
