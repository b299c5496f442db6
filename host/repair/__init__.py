"""Repair planning: from a diagnosis to a partially ordered, verified-valid repair plan.

A pipeline of pure stages after pyperplan (parse -> ground -> task -> search): ``domain``
parses ``models/<robot>/repair.pddl`` with the ``pddl`` library; ``problem`` builds paper 000
§IV-E's I and G from a diagnosis and the observations; ``grounding`` instantiates the
domain over the robot's components into a ``task`` of bit masks; ``protect`` removes every
operator that would switch off a protected component; ``search`` holds our planners (an optimal
A* with relevance pruning and stubborn sets, a BFS reference) and ``downward`` runs Fast
Downward, all behind ``planner.PLANNERS``; ``plan`` deorders the result into a
partial order an executor can run in parallel; ``policy`` picks which of several diagnoses
to repair and records why. ``planner.RepairPlanner`` wires the stages::

    planner = RepairPlanner.for_system("models/tedusar")
    plan = planner.plan({"jaguar"}, observations)      # a Plan
    for step in plan.ready(done=set()): ...            # steps whose predecessors are done
"""

from __future__ import annotations

from host.repair.errors import DomainError, NoPlanError, PlanningLimitError, ProblemError
from host.repair.plan import Plan, Step
from host.repair.planner import RepairPlanner
from host.repair.policy import Candidate, Choice, choose
from host.repair.problem import RepairModel, RepairProblem, build_problem, repair_model

__all__ = [
    "Candidate",
    "Choice",
    "DomainError",
    "NoPlanError",
    "Plan",
    "PlanningLimitError",
    "ProblemError",
    "RepairModel",
    "RepairPlanner",
    "RepairProblem",
    "Step",
    "build_problem",
    "choose",
    "repair_model",
]
