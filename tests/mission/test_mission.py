"""Layer 3, the mission (``host.mission``), over layers 1-2 and the real world: the dispatcher
refuses an action whose precondition the KB lacks, observations override the KB, a fault-free
mission completes, a lidar hang repaired by layer 0 is absorbed below the mission layer, and a
quarantined lidar makes the mission stop with an explanation naming it."""

from __future__ import annotations

import asyncio

from host.events import Dispatch, KbChange, LayerResult, MissionState, TreeChange
from host.layers import EXECUTIVE, MISSION
from host.mission.dispatcher import DispatchOutcome
from host.planning.temporal_planner import Scheduled, ground
from tests.mission.harness import Harness, until


def step(h: Harness, name: str, *args: str) -> Scheduled:
    prob = h.files.problem
    g = next(g for g in ground(h.files.domain, prob) if g.name == name and g.args == args)
    return Scheduled(g, 0.0)


async def test_dispatch_with_a_failed_precondition_is_refused_and_nothing_runs(
        h: Harness) -> None:
    runner = h.runner()
    runner.kb.change([(a, True) for a in h.files.problem.init], "init")
    done = await runner.dispatcher.dispatch(step(h, "navigate", "corridor", "office",
                                                 "door_office"), 0)
    assert done.outcome is DispatchOutcome.REFUSED and not done.result.success
    d, = h.of(Dispatch)
    assert not d.ok and "(at entrance)" in d.kb
    assert [(c.atom, c.when) for c in d.failed_checks] == [("(at corridor)", "start"),
                                                            ("(level)", "start")]
    assert ("(connects door_office corridor office)", "start") in [
        (c.atom, c.when) for c in d.checks if c.held]  # static conditions are checked too
    assert not [e for e in h.of(LayerResult) if e.layer == EXECUTIVE]  # never dispatched
    assert h.world.arena.place() == "entrance"
    r, = h.of(LayerResult)
    assert r.layer == MISSION
    assert "refused: (at corridor), (level) does not hold" in r.explanation[0].what


async def test_an_observation_overrides_the_knowledge_base(h: Harness) -> None:
    runner = h.runner()
    runner.kb.change([(a, True) for a in h.files.problem.init], "init")
    assert ("open", "door_lab") in runner.kb.atoms  # the problem believes it open
    overridden = await runner.dispatcher.sense(None, "at the start")
    assert overridden == [(("open", "door_lab"), False)]  # the world shows it closed
    change = h.of(KbChange)[-1]
    assert change.source == "sensing" and change.removed == ("(open door_lab)",)
    assert ("open", "door_lab") not in runner.kb.atoms


async def test_a_fault_free_mission_completes_and_marks_every_victim(h: Harness) -> None:
    outcome = await asyncio.wait_for(h.runner().run(), 240)
    assert outcome.completed, outcome.detail
    assert sorted(h.world.arena.marked) == ["victim_1", "victim_2"]
    states = [e.state for e in h.of(MissionState)]
    assert states[0] == "started" and states[-1] == "completed" and "planned" in states
    assert all(e.success for e in h.of(LayerResult))
    assert all(d.ok for d in h.of(Dispatch))


async def test_a_lidar_hang_repaired_by_layer_0_is_handled_below_the_mission(
        h: Harness) -> None:
    mission = asyncio.ensure_future(h.runner().run())

    def driving() -> bool:
        act = h.world.active
        return act is not None and act.goal.skill == "navigate" and act.goal.fraction() > 0.2

    await until(driving, "the robot driving", 120)
    h.truth.blocked_by["lidar"] = "no laser scans"  # the Hokuyo hangs
    h.repairing("hokuyo")
    await until(lambda: any(e.detail.startswith("holding: layer 0: hokuyo")
                            for e in h.of(TreeChange)), "the guard holding", 60)
    await asyncio.sleep(1.0)
    del h.truth.blocked_by["lidar"]  # power-cycled, its driver restarted
    h.repaired()
    outcome = await asyncio.wait_for(mission, 240)
    assert outcome.completed, outcome.detail
    assert all(e.success for e in h.of(LayerResult) if e.layer in (EXECUTIVE, MISSION))
    assert not [e for e in h.of(MissionState) if e.state == "replanning"
                and "hokuyo" in e.detail]


async def test_a_quarantined_lidar_stops_the_mission_naming_it(h: Harness) -> None:
    h.quarantine("hokuyo")
    outcome = await asyncio.wait_for(h.runner().run(), 60)
    assert not outcome.completed and outcome.components == ["hokuyo"]
    assert "navigate unavailable (hokuyo is quarantined" in outcome.detail
    last = h.of(MissionState)[-1]
    assert last.state == "stopped" and last.components == ("hokuyo",)
    assert h.world.arena.place() == "entrance"


async def test_every_dispatch_leaves_the_history_plan_execution_diagnosis_replays(
        h: Harness) -> None:
    """Issue 16 reads the journal: per dispatch the ground action, the KB before, each checked
    condition and its outcome, start and end, the result, the observations that overrode the
    KB, and the KB after — all joined by the dispatch id."""
    outcome = await asyncio.wait_for(h.runner().run(), 240)
    assert outcome.completed, outcome.detail
    results = {e.dispatch_id: e for e in h.of(LayerResult) if e.layer == MISSION}
    for d in h.of(Dispatch):
        assert d.ok and all(c.held for c in d.checks)
        assert d.checks or d.action == "level_laser"  # the one action without conditions
        r = results[d.dispatch_id]
        assert (r.command, r.args) == (d.action, d.args) and r.started <= r.finished
        assert (r.kb and r.kb != d.kb) or d.action == "search_room"
    search = next(d for d in h.of(Dispatch) if d.action == "search_room"
                  and d.args == ("office",))
    sensed = [e for e in h.of(KbChange) if e.dispatch_id == search.dispatch_id
              and e.source == "sensing"]
    assert sensed and "(victim-in victim_1 office)" in sensed[0].added
    assert "(victim-in victim_1 office)" in results[search.dispatch_id].kb
    assert "(victim-in victim_1 office)" not in search.kb


async def test_an_action_the_world_defeats_is_not_replanned_and_the_stop_says_why(
        h: Harness) -> None:
    h.world.arena.robot.action_execution_options["open"].success_probability = 0.0
    outcome = await asyncio.wait_for(h.runner().run(), 240)
    assert not outcome.completed and outcome.components == []
    assert "cannot reach" in outcome.detail and "(searched lab)" in outcome.detail
    assert "failed from here: open_door(door_lab, corridor, lab)" in outcome.detail
    assert "simulated open failure" in outcome.detail
    opened = [d for d in h.of(Dispatch) if d.action == "open_door"]
    assert len(opened) == 1  # tried (three times, by the tree), then planned around: no way
    assert h.of(MissionState)[-1].state == "stopped"


async def test_the_flat_system_aborts_the_action_and_replans_from_where_it_stopped(
        h: Harness) -> None:
    mission = asyncio.ensure_future(h.runner(flat=True).run())

    def driving() -> bool:
        act = h.world.active
        return act is not None and act.goal.skill == "navigate" and act.goal.fraction() > 0.2

    await until(driving, "the robot driving", 120)
    h.truth.blocked_by["lidar"] = "no laser scans"
    h.repairing("hokuyo")
    await until(lambda: any(e.layer == MISSION and not e.success for e in h.of(LayerResult)),
                "the action failing at the mission layer", 60)
    del h.truth.blocked_by["lidar"]
    h.repaired()
    outcome = await asyncio.wait_for(mission, 240)
    assert outcome.completed, outcome.detail
    failed = [e for e in h.of(LayerResult) if e.layer == MISSION and not e.success]
    assert failed[0].command == "navigate" and "hokuyo" in failed[0].explanation[-1].components
    assert "its inputs stopped (waiting: no laser scans)" in failed[0].explanation[-1].what
    assert any(e.state == "replanning" and "hokuyo" in e.detail for e in h.of(MissionState))
    assert not any(isinstance(e, TreeChange) and e.detail.startswith("holding")
                   for e in h.events)  # no guards in the flat system
