"""Partial-order plans: what an executor may start, in which rounds, as JSON."""

from __future__ import annotations

from host.diagnosis.logic import parse_literal
from host.repair.planner import RepairPlanner


def test_ready_steps_follow_the_partial_order(tedusar: RepairPlanner) -> None:
    obs = [parse_literal("~on(jaguar)"), parse_literal("~running(hokuyo_node)")]
    plan = tedusar.plan({"jaguar", "hokuyo_node"}, obs)
    names = {s.id: str(s) for s in plan.steps}
    first = {names[s.id] for s in plan.ready(done=set())}
    assert first == {"power_up(jaguar)", "start_node(hokuyo_node)"}
    power_up = next(i for i, n in names.items() if n == "power_up(jaguar)")
    hokuyo = next(i for i, n in names.items() if n == "start_node(hokuyo_node)")
    # a started step is not offered twice; finishing it releases its successors
    assert {names[s.id] for s in plan.ready(done=set(), started={power_up})} == {
        "start_node(hokuyo_node)"}
    assert {names[s.id] for s in plan.ready(done={power_up, hokuyo})} == {
        "stop_node(jaguar_node)"}
    assert [sorted(str(s) for s in layer) for layer in plan.layers()] == [
        ["power_up(jaguar)", "start_node(hokuyo_node)"],
        ["stop_node(jaguar_node)"],
        ["start_node(jaguar_node)"],
    ]
    js = plan.to_json()
    assert [len(layer) for layer in js["layers"]] == [2, 1, 1]
    assert js["cost"] == 4.0 and js["planner"] == "astar"
