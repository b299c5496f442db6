"""Layer 2, the executive (``host.executive``): a mission action as a behaviour tree over the
real world's skills — a guard that holds the tree while layer 0 repairs, bounded retry, a
failure that goes up with its subtask and explanation, and the tick trace."""

from __future__ import annotations

import asyncio

from host.events import LayerResult, TreeChange
from host.executive import Executive
from host.layers import EXECUTIVE, SKILLS, Command
from host.skills import Skill
from tests.mission.harness import Harness, until


def executive(h: Harness, flat: bool = False, max_hold_s: float = 120.0) -> Executive:
    assert h.client is not None
    skills = {n: Skill(s, h.client, h.layer0, h.clock, flat=flat)
              for n, s in h.files.skills.items()}
    params = {a: act.param_names for a, act in h.files.domain.actions.items()}
    return Executive(h.files.recipes, params, skills, h.layer0, h.clock, h.emit,
                     max_hold_s=max_hold_s, flat=flat)


def nav(to: str, door: str) -> Command:
    return Command(EXECUTIVE, "navigate", ("entrance", to, door))


async def test_a_guard_holds_the_tree_during_a_repair_and_the_action_resumes(h: Harness) -> None:
    h.repairing("hokuyo")
    task = asyncio.ensure_future(executive(h).execute(nav("corridor", "door_entrance"), "d1"))

    def holding() -> bool:
        return any(e.status == "RUNNING" and e.detail.startswith("holding: layer 0: hokuyo")
                   for e in h.of(TreeChange))

    await until(holding, "the guard holding")
    await asyncio.sleep(0.5)
    assert not task.done() and h.world.active is None  # held: the skill never started
    h.repaired()
    result = await asyncio.wait_for(task, 60)
    assert result.success and result.data["place"] == "corridor"
    assert all(e.dispatch_id == "d1" for e in h.of(TreeChange))
    assert [(e.layer, e.success) for e in h.of(LayerResult)] == [(SKILLS, True),
                                                                 (EXECUTIVE, True)]


async def test_retries_exhausted_fail_with_the_subtask_and_the_explanation_below(
        h: Harness) -> None:
    result = await asyncio.wait_for(executive(h).execute(nav("lab", "door_lab"), "d2"), 60)
    assert not result.success
    assert result.explanation[0].layer == EXECUTIVE
    assert result.explanation[0].what == ("navigate(entrance, lab, door_lab): subtask "
                                          "'navigate(lab)' failed (3 attempts)")
    assert "no path from entrance to lab (closed: door_lab)" in result.explanation[1].what
    skill_results = [e for e in h.of(LayerResult) if e.layer == SKILLS]
    assert len(skill_results) == 3 and not any(e.success for e in skill_results)


async def test_a_quarantine_fails_the_guard_at_once_naming_the_component(h: Harness) -> None:
    h.quarantine("hokuyo")
    result = await asyncio.wait_for(executive(h).execute(nav("corridor", "door_entrance")), 60)
    assert not result.success and result.components() == ["hokuyo"]
    assert "navigate available: hokuyo is quarantined" in result.describe()
    assert h.world.active is None and h.world.arena.place() == "entrance"


async def test_a_hold_longer_than_allowed_fails_the_action(h: Harness) -> None:
    h.repairing("hokuyo")
    ex = executive(h, max_hold_s=0.5)
    result = await asyncio.wait_for(ex.execute(nav("corridor", "door_entrance")), 60)
    assert not result.success and result.components() == ["hokuyo"]
    assert "longer than 0.5 s" in result.describe()
