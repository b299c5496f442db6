"""The planning pipeline for one robot: diagnosis -> problem -> search -> partial-order plan.

``RepairPlanner(domain, model)`` grounds the domain over the model once (the task depends
on the model only; each object typed as the domain can take it, ``problem.domain_type``) and
removes the operators that would switch off protected components;
``plan(bad, observations)`` then builds the problem of that diagnosis (paper 000 §IV-E),
checks by relaxed reachability that every goal can be reached at all (and says which
component cannot be repaired, and why, when one cannot), runs a planner from the registry
(``astar`` by default), validates the returned sequence step by step against the task (any
planner's plan, ours or Fast Downward's), and returns it deordered into a ``Plan`` an
executor can run in parallel where steps are independent. Nothing here acts on the robot:
planning is a dry run by nature. The domain's own words for abnormal / healthy / powered /
running (``vocabulary``) shape I and G, so the original system's domain plans as well as ours.
``for_system`` takes a robot directory or a tug model file (``theory_model``).
"""

from __future__ import annotations

import logging
from collections.abc import Iterable
from pathlib import Path
from typing import TYPE_CHECKING

from host.planning.domain import DOMAIN_FILE, ROOT_TYPE, Domain, PddlAtom, load_domain
from host.planning.errors import DomainError, NoPlanError, ProblemError
from host.planning.grounding import ground
from host.planning.plan import Plan, deorder, stops_first
from host.planning.planners import PLANNERS, unreachable, validate
from host.planning.search import (
    DEFAULT_MAX_EXPANSIONS,
    SearchInput,
    relevant_ops,
)
from host.planning.task import Task, lit_atom
from host.planning.vocabulary import Vocabulary
from host.repair.external import (
    lifecycle_nodes,
    load_external,
    not_repairable,
    with_external,
)
from host.repair.problem import (
    RepairModel,
    RepairProblem,
    build_problem,
    domain_type,
    repair_model,
    to_pddl,
)
from host.repair.protect import check_plan, enforce

if TYPE_CHECKING:
    from host.diagnosis.logic import Literal

log = logging.getLogger(__name__)

class RepairPlanner:
    """Plans repairs for one robot model with one domain."""

    def __init__(self, domain: Domain, model: RepairModel) -> None:
        domain.vocabulary.require_health(str(domain.path))
        self.domain = domain
        self.model = model
        declared = {*domain.types, *domain.types.values(), ROOT_TYPE}
        #: each object's type in the domain (a driver is a node where the domain has no driver)
        self.objects = {name: domain_type(t, declared) for name, t in model.types.items()}
        self._full: Task | None = None
        self._task: Task | None = None
        self._goal: tuple[tuple[PddlAtom, ...], tuple[int, ...]] | None = None

    @classmethod
    def for_system(cls, system_dir: str | Path, domain_path: str | Path | None = None,
                   managed: Iterable[str] = ()) -> RepairPlanner:
        """Load ``SYSTEM_DIR/system.yaml`` and ``repair.pddl`` (or ``domain_path``).
        ``system_dir`` may be a tug model file; its domain is ``domain_path`` or the
        ``repair.pddl`` beside it. ``managed``: the robot's ROS 2 managed nodes (used when
        the domain has ``managed``); the nodes started elsewhere (``external:``,
        ``host.repair.external``) are added, the lifecycle ones as managed."""
        from host.diagnosis.files import load_theory
        from host.diagnosis.model import SYSTEM_FILE, load_system
        from host.repair.theory_model import repair_model_of

        path = Path(system_dir)
        if path.is_dir() or path.name == SYSTEM_FILE:
            domain = load_domain(domain_path if domain_path is not None else path)
            system = load_system(path)
            external = load_external(path, system)
            managed = [*managed, *lifecycle_nodes(external)]
            if "managed" not in domain.predicates:
                managed = []
            return cls(domain, with_external(repair_model(system, managed), external))
        theory = load_theory(path)
        model = repair_model_of(theory, path.stem)
        if domain_path is None:
            domain_path = path.parent / DOMAIN_FILE
            if not domain_path.exists():
                raise DomainError(f"{path}: a tug model file has no repair domain beside it",
                                  "give the domain with --domain FILE")
        return cls(load_domain(domain_path), model)

    @property
    def vocabulary(self) -> Vocabulary:
        """The domain's words for abnormal / healthy / powered / running."""
        return self.domain.vocabulary

    @property
    def task(self) -> Task:
        """The ground task with the protected components' switch-offs removed (cached)."""
        if self._task is None:
            static = [a for a in self.model.static_facts() if a.pred in self.domain.predicates]
            self._full = ground(self.domain, self.objects, static)
            self._task = enforce(self._full, self.model.protected, self.vocabulary)
        return self._task

    def problem(self, bad: Iterable[str], observations: Iterable[Literal] = ()) -> RepairProblem:
        return build_problem(self.model, bad, observations, self.vocabulary)

    def problem_pddl(self, problem: RepairProblem) -> str:
        """``problem`` as a PDDL file of this domain."""
        return to_pddl(problem, self.domain.name, types=self.objects,
                       predicates=self.domain.predicates)

    def plan(
        self,
        bad: Iterable[str],
        observations: Iterable[Literal] = (),
        planner: str = "astar",
        max_expansions: int = DEFAULT_MAX_EXPANSIONS,
    ) -> Plan:
        """The repair plan for the diagnosis ``bad``; raises ``NoPlanError`` if none exists."""
        return self.plan_problem(self.problem(bad, observations), planner, max_expansions)

    def plan_problem(
        self,
        problem: RepairProblem,
        planner: str = "astar",
        max_expansions: int = DEFAULT_MAX_EXPANSIONS,
    ) -> Plan:
        search = PLANNERS.get(planner)
        if search is None:
            raise ProblemError(
                f"unknown planner {planner!r}", f"choose one of {', '.join(sorted(PLANNERS))}"
            )
        task = self.task
        init = task.state((a.pred, a.args) for a in problem.init)
        goal = self._goal_literals(task, problem)
        relevant = self._check_reachable(task, init, goal)
        pddl = self.problem_pddl(problem) if planner == "fast-downward" else None
        result = search(
            SearchInput(task, init, goal, self.domain.path, pddl, max_expansions, relevant)
        )
        if result.ops is None:
            raise NoPlanError(
                "no plan reaches the goal: the repairs needed interfere with each other",
                "check the domain's preconditions against system.yaml",
            )
        ops = [task.ops[i] for i in result.ops]
        validate(task, init, goal, ops, planner)
        ops = stops_first(ops, init, goal)
        check_plan(task, ops, self.model.protected, self.vocabulary)
        notes = [f"assumed {a} (not observed)" for a in problem.assumed]
        cost = sum(op.cost for op in ops)
        log.debug("plan by %s: %d steps, stats %s", planner, len(ops), result.stats)
        return deorder(ops, cost, planner, notes)

    def _goal_literals(self, task: Task, problem: RepairProblem) -> tuple[int, ...]:
        """G as literals; the goal is the same for every diagnosis, so it is cached."""
        if self._goal is None or self._goal[0] != problem.goal:
            lits = tuple(task.literal(a.pred, a.args, problem.goal_holds) for a in problem.goal)
            self._goal = (problem.goal, lits)
        return self._goal[1]

    def _check_reachable(self, task: Task, init: int, goal: tuple[int, ...]) -> list[int]:
        """The relevant operators, after making sure every goal is reachable with them."""
        subset = relevant_ops(task, init, goal)
        missing = unreachable(task, init, goal, subset)
        if not missing:
            return subset
        why = {x: self._why(task, x) for x in missing}
        roots = [r for r in why.values() if r is not None]
        follow = [task.atoms[lit_atom(x)][1][0] for x, r in why.items() if r is None]
        if follow:
            names = ", ".join(follow[:6]) + (", ..." if len(follow) > 6 else "")
            if roots:
                roots.append(f"and {len(follow)} that need them stay abnormal ({names})")
            else:
                roots.append(f"{names}: what their repair needs cannot be reached")
        raise NoPlanError(
            "no plan reaches the goal: " + "; ".join(roots),
            "repair these by hand, or add the action that repairs them to "
            f"{self.domain.path.name}",
            tuple(task.describe(x) for x in missing),
        )

    def _why(self, task: Task, goal_lit: int) -> str | None:
        """Why a goal literal is unreachable, or None when only what it needs is."""
        pred, args = task.atoms[lit_atom(goal_lit)]
        name = args[0] if args else task.describe(goal_lit)
        health = (self.vocabulary.abnormal, self.vocabulary.healthy)
        what = (f"{name} stays abnormal" if pred in health
                else f"{task.describe(goal_lit)} unreachable")
        full = self._full if self._full is not None else task
        achievers = [full.ops[i] for i in full.achievers().get(goal_lit, ())]
        removed = {label for label, _ in task.removed}
        blocked = [op.label() for op in achievers if op.label() in removed]
        if achievers and len(blocked) == len(achievers):
            return f"{what}: only {', '.join(blocked)} would repair it, and that switches off a "\
                "protected component"
        if blocked:
            return f"{what}: {', '.join(blocked)} would switch off a protected component and "\
                "no other repair can become applicable"
        if name in self.model.external and name not in self.model.managed \
                and name not in self.model.restartable:
            return f"{what}: {not_repairable(name)}"
        if not achievers:
            typ = self.model.types.get(name, "?")
            return f"{what}: no action of the domain repairs a {typ}"
        return None
