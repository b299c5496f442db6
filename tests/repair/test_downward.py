"""The Fast Downward adapter maps its plan onto our task and refuses forbidden steps.

The driver itself is an optional extra (``.[bench]``, exercised by benchmarks/planning.py);
here its run is replaced by what it would print, so the mapping is tested without it.
"""

from __future__ import annotations

from pathlib import Path

import pytest

from host.diagnosis.logic import parse_literal
from host.errors import DxboardError
from host.planning import downward
from host.planning.downward import DownwardRun
from host.planning.errors import NoPlanError
from host.repair.planner import RepairPlanner


def _fake(steps: list[tuple[str, tuple[str, ...]]] | None, seen: dict[str, str]) -> object:
    def run(domain: Path, problem: Path, workdir: Path, search: str = "",
            time_limit: int = 0) -> DownwardRun:
        seen["domain"] = str(domain)
        seen["problem"] = problem.read_text()
        return DownwardRun(steps, 0.1, 0.05, 0.05)
    return run


def test_plan_lines_become_our_steps(
    tedusar: RepairPlanner, monkeypatch: pytest.MonkeyPatch
) -> None:
    seen: dict[str, str] = {}
    monkeypatch.setattr(downward, "run_fast_downward", _fake([
        ("POWER_UP", ("jaguar",)), ("stop_node", ("jaguar_node",)),
        ("start_node", ("jaguar_node",))], seen))
    plan = tedusar.plan({"jaguar"}, [parse_literal("~on(jaguar)")], planner="fast-downward")
    assert [str(s) for s in plan.steps] == [
        "power_up(jaguar)", "stop_node(jaguar_node)", "start_node(jaguar_node)"]
    assert plan.planner == "fast-downward"
    assert seen["domain"].endswith("repair.pddl") and "(ab jaguar)" in seen["problem"]


def test_forbidden_step_from_fast_downward_is_refused(
    tedusar: RepairPlanner, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setattr(downward, "run_fast_downward", _fake([
        ("power_cycle", ("channel2",)), ("power_up", ("jaguar",))], {}))
    with pytest.raises(NoPlanError, match="protected"):
        tedusar.plan({"jaguar"}, planner="fast-downward")


def test_invalid_plan_from_an_external_planner_is_caught(
    tedusar: RepairPlanner, monkeypatch: pytest.MonkeyPatch
) -> None:
    # start before power: not applicable, so the validation step rejects it
    monkeypatch.setattr(downward, "run_fast_downward", _fake([
        ("stop_node", ("jaguar_node",)), ("start_node", ("jaguar_node",)),
        ("power_up", ("jaguar",))], {}))
    with pytest.raises(DxboardError, match="not applicable"):
        tedusar.plan({"jaguar"}, planner="fast-downward")


def test_unsolvable_answer_is_reported(
    tedusar: RepairPlanner, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setattr(downward, "run_fast_downward", _fake(None, {}))
    with pytest.raises(NoPlanError, match="no plan"):
        tedusar.plan({"jaguar"}, planner="fast-downward")
