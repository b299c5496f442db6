"""Layer 1, the skills (``host.skills``): a goal of the real world's skill servers, monitored
(progress, stall, timeout, resources) and explained with layer 0's words."""

from __future__ import annotations

import asyncio

from host.events import ActionRecord, ActionState, DiagnosisRecord, PlanRecord, PlanStep
from host.layers import SKILLS, Command
from host.skills import AvailState, Skill, SkillSpec
from tests.mission.harness import Harness, until

NAV = SkillSpec("navigate", ("jaguar", "jaguar_node", "hokuyo", "hokuyo_node", "/scan"),
                timeout_s=120, stall_s=1.0)
TO_OFFICE = Command(SKILLS, "navigate", ("office",), {"to": "office"})


def skill(h: Harness, flat: bool = False, spec: SkillSpec = NAV) -> Skill:
    assert h.client is not None
    return Skill(spec, h.client, h.layer0, h.clock, flat=flat)


async def test_a_quarantined_component_makes_the_skill_unavailable_without_a_goal(
        h: Harness) -> None:
    h.quarantine("hokuyo")
    result = await skill(h).execute(TO_OFFICE)
    assert not result.success and result.components() == ["hokuyo"]
    assert "navigate is unavailable: hokuyo is quarantined" in result.describe()
    assert h.world.active is None and h.world.arena.place() == "entrance"  # nothing was sent


async def test_a_stall_while_layer_0_repairs_is_not_a_failure_and_the_skill_resumes(
        h: Harness) -> None:
    h.truth.blocked_by["lidar"] = "no laser scans"
    h.repairing("hokuyo")
    task = asyncio.ensure_future(skill(h).execute(TO_OFFICE))
    await until(lambda: h.world.active is not None, "the goal in the world")
    await asyncio.sleep(NAV.stall_s * 3)  # three stall periods without progress: held
    assert not task.done()
    del h.truth.blocked_by["lidar"]
    h.repaired()
    result = await asyncio.wait_for(task, 60)
    assert result.success and result.data["place"] == "office"


async def test_a_flat_skill_aborts_when_its_inputs_stop_and_blames_what_layer_0_diagnosed(
        h: Harness) -> None:
    h.truth.blocked_by["lidar"] = "no laser scans"
    h.repairing("hokuyo")
    patient = SkillSpec(NAV.name, NAV.needs, timeout_s=120, stall_s=60)
    result = await asyncio.wait_for(skill(h, True, patient).execute(TO_OFFICE), 60)
    assert not result.success and result.components() == ["hokuyo"]
    assert "navigate aborted at 0%: its inputs stopped (waiting: no laser scans)" in \
        result.describe()
    await until(lambda: h.world.active is None, "the goal canceled in the world")


async def test_a_failure_with_every_component_working_is_blamed_on_the_world(
        h: Harness) -> None:
    result = await skill(h).execute(Command(SKILLS, "navigate", ("lab",), {"to": "lab"}))
    assert not result.success and result.components() == []
    assert "no path from entrance to lab (closed: door_lab)" in result.describe()
    assert "layer 0 finds every component it needs working" in result.describe()


def test_layer_0_holds_a_skill_only_while_what_it_needs_is_abnormal_or_worked_on() -> None:
    h = Harness()  # no world needed: layer 0 as the daemon's events say it
    needs = NAV.needs
    h.say(DiagnosisRecord((("hokuyo",),)))
    assert h.layer0.availability(needs).state is AvailState.HOLD
    h.say(PlanRecord("p1", (PlanStep("power_cycle", ("hokuyo",)),
                            PlanStep("restart_node", ("imu_node",))), ("hokuyo", "imu_node")))
    h.say(ActionRecord("a1", "power_cycle", ("hokuyo",), ActionState.STARTED, 1.0))
    h.say(DiagnosisRecord(((),)))  # the observers see it working again, the action still runs
    hold = h.layer0.availability(needs)
    assert hold.state is AvailState.HOLD and hold.components == ("hokuyo",)
    assert hold.why == "layer 0: hokuyo repairing"
    h.say(ActionRecord("a1", "power_cycle", ("hokuyo",), ActionState.SUCCEEDED, 1.0, 2.0))
    h.say(ActionRecord("a2", "restart_node", ("imu_node",), ActionState.STARTED, 2.0))
    assert h.layer0.availability(needs).ok  # the repair goes on, but not on what it needs
    assert h.layer0.availability(("imu_node",)).state is AvailState.HOLD
    h.quarantine("hokuyo")
    gone = h.layer0.availability(needs)
    assert gone.state is AvailState.UNAVAILABLE and gone.components == ("hokuyo",)
