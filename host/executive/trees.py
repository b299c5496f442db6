"""φ from layer 3 to layer 1: each mission action refined into a behaviour tree (py_trees).

A ``Recipe`` says how an action of the mission's domain is carried out: ``do`` (skills in
order), an optional ``fallback`` (other skills to try when ``do`` fails) and ``retries`` (how
many more times the whole is tried). A step names a skill and its arguments, ``?x`` taking the
action's parameter ``?x``. In ``mission.yaml``::

    actions:
      navigate: {do: [{navigate: {to: "?to"}}], retries: 2}
      mark_victim: {do: [{mark: {victim: "?v"}}], fallback: [detect, {mark: {victim: "?v"}}]}

``build`` makes the dependable tree of paper 001 §II-B::

    Retry(retries + 1)
      Selector (memory)                   only with a fallback
        Sequence (memory)  "do"           the steps one after another, each
          Sequence (no memory)              a reactive sequence: its guard re-checked on
            Guard(needs of the skill)       every tick holds (RUNNING) or fails it
            SkillAction(skill, args)
        Sequence (memory)  "fallback"

and with ``flat`` the baseline without the layers' hand-over: the skills in a sequence, no
guards, no retry (a failure goes straight up). ``RecipeError`` names the action and the fix.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import Any

import py_trees

from host.events import Event
from host.executive.nodes import Guard, SkillAction, Trace
from host.layers import SKILLS, Command
from host.skills import Layer0View, Skill


class RecipeError(ValueError):
    """A recipe is malformed; the message names the action and the fix."""


@dataclass(frozen=True)
class RecipeStep:
    skill: str
    args: tuple[tuple[str, str], ...] = ()  # (name, value or ?parameter)

    def bind(self, params: Mapping[str, str]) -> Command:
        values = {k: params.get(v, v) if v.startswith("?") else v for k, v in self.args}
        return Command(SKILLS, self.skill, tuple(values.values()), values)

    def __str__(self) -> str:
        return self.skill + (f"({', '.join(f'{k}={v}' for k, v in self.args)})"
                             if self.args else "")


@dataclass(frozen=True)
class Recipe:
    action: str
    do: tuple[RecipeStep, ...]
    fallback: tuple[RecipeStep, ...] = ()
    retries: int = 0

    def skills(self) -> set[str]:
        return {s.skill for s in self.do + self.fallback}


def _step(action: str, raw: Any) -> RecipeStep:
    if isinstance(raw, str) and raw:
        return RecipeStep(raw)
    if isinstance(raw, dict) and len(raw) == 1:
        (skill, args), = raw.items()
        if isinstance(skill, str) and (args is None or isinstance(args, dict)) \
                and all(isinstance(k, str) and isinstance(v, str) for k, v in
                        (args or {}).items()):
            return RecipeStep(skill, tuple((args or {}).items()))
    raise RecipeError(f"action {action}: a step is a skill name or {{skill: {{arg: value}}}}, "
                      f"not {raw!r}")


def parse_recipe(action: str, raw: Any) -> Recipe:
    if not isinstance(raw, dict) or not isinstance(raw.get("do"), list) or not raw["do"]:
        raise RecipeError(f"action {action}: give {{do: [skill, ...], fallback: [...], "
                          f"retries: N}}, not {raw!r}")
    bad = set(raw) - {"do", "fallback", "retries"}
    if bad:
        raise RecipeError(f"action {action}: unknown field {sorted(bad)[0]!r} "
                          "(known: do, fallback, retries)")
    retries = raw.get("retries", 0)
    if not isinstance(retries, int) or isinstance(retries, bool) or not 0 <= retries <= 10:
        raise RecipeError(f"action {action}: retries must be 0..10, not {retries!r}")
    fallback = raw.get("fallback") or []
    if not isinstance(fallback, list):
        raise RecipeError(f"action {action}: fallback must be a list of steps")
    return Recipe(action, tuple(_step(action, s) for s in raw["do"]),
                  tuple(_step(action, s) for s in fallback), retries)


@dataclass
class TreeContext:
    """What the leaves of one tree share."""

    skills: Mapping[str, Skill]
    layer0: Layer0View
    clock: Callable[[], float]
    emit: Callable[[Event], None]
    trace: Trace
    max_hold_s: float = 120.0
    dispatch_id: str = ""


def build(recipe: Recipe, params: Mapping[str, str], ctx: TreeContext,
          flat: bool = False) -> py_trees.behaviour.Behaviour:
    """The tree for one dispatch of ``recipe``'s action with ``params`` (``?x`` -> value)."""

    def action(step: RecipeStep) -> py_trees.behaviour.Behaviour:
        cmd = step.bind(params)
        return SkillAction(str(cmd), ctx.skills[step.skill], cmd, ctx.trace, ctx.clock,
                           ctx.emit, ctx.dispatch_id)

    def guarded(step: RecipeStep) -> py_trees.behaviour.Behaviour:
        cmd = step.bind(params)
        guard = Guard(f"{step.skill} available", ctx.skills[step.skill].spec.needs, ctx.layer0,
                      ctx.clock, ctx.trace, ctx.max_hold_s)
        return py_trees.composites.Sequence(f"guarded {cmd}", memory=False,
                                            children=[guard, action(step)])

    if flat:
        return py_trees.composites.Sequence(recipe.action, memory=True,
                                            children=[action(s) for s in recipe.do])
    body: py_trees.behaviour.Behaviour = py_trees.composites.Sequence(
        "do", memory=True, children=[guarded(s) for s in recipe.do])
    if recipe.fallback:
        other = py_trees.composites.Sequence("fallback", memory=True,
                                             children=[guarded(s) for s in recipe.fallback])
        body = py_trees.composites.Selector("do or fallback", memory=True,
                                            children=[body, other])
    return py_trees.decorators.Retry(recipe.action, body, recipe.retries + 1)
