"""A robot's mission, read and checked: ``SYSTEM_DIR/mission/mission.yaml`` and its PDDL files.

``mission.yaml`` (see ``models/tedusar/mission/mission.yaml``) names the temporal PDDL
``domain`` and ``problem`` (``host.planning.temporal_pddl``), the goal reasoner's ``goals`` rules,
``sensing`` (ψ: the world's state in the domain's predicates), the ``skills`` (layer 1: what
each needs of layer 0, its monitor's limits), the ``actions`` (layer 2: a behaviour-tree recipe
per domain action) and ``max_hold_s``. ``load_mission`` checks that they fit together and with
the robot's model — every domain action has a recipe, every recipe's skills are declared and its
``?x`` are the action's parameters, every need is a component or topic of ``system.yaml`` —
and raises a ``UserError`` naming the file, the entry and the fix before anything starts.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any

from host.diagnosis import yamlpos
from host.diagnosis.model import SystemModel
from host.errors import UserError
from host.executive.trees import Recipe, RecipeError, parse_recipe
from host.mission.runner import GoalRule
from host.mission.sensing import KEYS, Sensing
from host.planning.temporal_pddl import PddlError, TemporalDomain, TemporalProblem, load, parse_atom
from host.skills.skill import SkillSpec

MISSION_DIR = "mission"
FILE = "mission.yaml"
FIELDS = {"domain", "problem", "goals", "sensing", "skills", "actions", "max_hold_s"}


@dataclass(frozen=True)
class MissionFiles:
    path: Path
    domain: TemporalDomain
    problem: TemporalProblem
    rules: tuple[GoalRule, ...]
    sensing: Sensing
    skills: dict[str, SkillSpec]
    recipes: dict[str, Recipe]
    max_hold_s: float

    def needs_of(self) -> dict[str, tuple[str, ...]]:
        """Each domain action -> what the skills of its recipe need of layer 0."""
        return {a: tuple(dict.fromkeys(n for s in sorted(r.skills())
                                       for n in self.skills[s].needs))
                for a, r in self.recipes.items()}


def _number(where: str, value: Any, lo: float = 0.0) -> float:
    if isinstance(value, bool) or not isinstance(value, int | float) or value <= lo:
        raise UserError(f"{where} must be a number above {lo:g}, not {value!r}", "fix the file")
    return float(value)


def _skills(path: Path, raw: Any, model: SystemModel | None) -> dict[str, SkillSpec]:
    if not isinstance(raw, dict) or not raw:
        raise UserError(f"{path}: 'skills' must map each skill to {{needs, timeout_s, stall_s}}",
                        "see models/tedusar/mission/mission.yaml")
    known = set() if model is None else set(model.components) | set(model.topics())
    out = {}
    for name, spec in raw.items():
        where = f"{path}: skill {name}"
        if not isinstance(spec, dict) or not isinstance(spec.get("needs"), list):
            raise UserError(f"{where}: give {{needs: [component or /topic, ...]}}",
                            "fix the file")
        bad = set(spec) - {"needs", "timeout_s", "stall_s"}
        if bad:
            raise UserError(f"{where}: unknown field {sorted(bad)[0]!r}",
                            "use needs, timeout_s, stall_s")
        needs = tuple(str(n) for n in spec["needs"])
        missing = [n for n in needs if model is not None and n not in known]
        if missing:
            raise UserError(f"{where}: needs {missing[0]!r}, which is no component or topic of "
                            "system.yaml", "name components and /topics of the robot's model")
        out[str(name)] = SkillSpec(str(name), needs,
                                   _number(f"{where}: timeout_s", spec.get("timeout_s", 120)),
                                   _number(f"{where}: stall_s", spec.get("stall_s", 10)))
    return out


def _recipes(path: Path, raw: Any, domain: TemporalDomain, skills: dict[str, SkillSpec]
             ) -> dict[str, Recipe]:
    if not isinstance(raw, dict):
        raise UserError(f"{path}: 'actions' must map each domain action to its recipe",
                        "see models/tedusar/mission/mission.yaml")
    out: dict[str, Recipe] = {}
    for name, spec in raw.items():
        if name not in domain.actions:
            raise UserError(f"{path}: actions: {name} is not an action of the domain",
                            f"use one of {', '.join(domain.actions)}")
        try:
            recipe = parse_recipe(str(name), spec)
        except RecipeError as exc:
            raise UserError(f"{path}: {exc}", "fix the recipe") from None
        params = set(domain.actions[name].param_names)
        for step in recipe.do + recipe.fallback:
            if step.skill not in skills:
                raise UserError(f"{path}: action {name}: skill {step.skill!r} is not declared "
                                "under skills", f"declare it, or use {', '.join(skills)}")
            for _, value in step.args:
                if value.startswith("?") and value not in params:
                    raise UserError(f"{path}: action {name}: {value} is not one of its "
                                    f"parameters ({', '.join(sorted(params)) or 'none'})",
                                    "fix the recipe")
        out[str(name)] = recipe
    missing = [a for a in domain.actions if a not in out]
    if missing:
        raise UserError(f"{path}: no recipe for the domain's action {missing[0]}",
                        "add it under actions")
    return out


def load_mission(system_dir: Path, model: SystemModel | None = None) -> MissionFiles:
    path = system_dir / MISSION_DIR / FILE
    if not path.is_file():
        raise UserError(f"{path}: no mission here", "give a robot directory with a mission, "
                        "e.g. models/tedusar")
    try:
        raw, _ = yamlpos.load(yamlpos.read_text(path), source=path)
    except yamlpos.YamlSyntaxError as exc:
        raise UserError(f"{path}:{exc.line}: {exc}", exc.fix) from None
    except (OSError, UnicodeDecodeError) as exc:
        raise UserError(f"{path}: cannot read it: {exc}", "fix the file") from None
    if not isinstance(raw, dict):
        raise UserError(f"{path}: expected a mapping", "see models/tedusar/mission/mission.yaml")
    bad = set(raw) - FIELDS
    if bad:
        raise UserError(f"{path}: unknown field {sorted(bad)[0]!r}",
                        f"known: {', '.join(sorted(FIELDS))}")
    for key in ("domain", "problem"):
        if not isinstance(raw.get(key), str):
            raise UserError(f"{path}: give '{key}: FILE.pddl'", "fix the file")
    try:
        domain, problem = load(path.parent / raw["domain"], path.parent / raw["problem"])
        rules = tuple(GoalRule(parse_atom(str(r["when"])), parse_atom(str(r["add"])))
                      for r in raw.get("goals") or [])
    except PddlError as exc:
        raise UserError(str(exc), "fix the PDDL") from None
    except (TypeError, KeyError):
        raise UserError(f"{path}: goals are [{{when: (atom ?x), add: (atom ?x)}}, ...]",
                        "fix the file") from None
    sensing_raw = raw.get("sensing") or {}
    if not isinstance(sensing_raw, dict) or set(sensing_raw) - set(KEYS):
        raise UserError(f"{path}: sensing takes {', '.join(KEYS)}", "fix the file")
    skills = _skills(path, raw.get("skills"), model)
    recipes = _recipes(path, raw.get("actions"), domain, skills)
    return MissionFiles(path, domain, problem, rules,
                        Sensing(**{k: str(v) for k, v in sensing_raw.items()}), skills, recipes,
                        _number(f"{path}: max_hold_s", raw.get("max_hold_s", 120)))
