"""Repair planning: from a diagnosis to a partially ordered, verified-valid repair plan.

The repair domain's own part of the planning pipeline; the generic PDDL stages (parse, ground,
task, search, partial-order plans) are ``host.planning``'s. ``problem`` builds paper 000
§IV-E's I and G from a diagnosis and the observations; ``protect`` removes every operator that
would switch off a protected component; ``planner.RepairPlanner`` grounds the domain over the
robot's components once and plans each diagnosis with a planner of
``host.planning.planners.PLANNERS``; ``policy`` picks which of several diagnoses to repair and
records why; ``executor`` and ``service`` carry a plan out on the robot::

    planner = RepairPlanner.for_system("models/tedusar")
    plan = planner.plan({"jaguar"}, observations)      # a host.planning.plan.Plan
    for step in plan.ready(done=set()): ...            # steps whose predecessors are done
"""

from __future__ import annotations

from host.repair.planner import RepairPlanner
from host.repair.policy import Candidate, Choice, choose
from host.repair.problem import RepairModel, RepairProblem, build_problem, repair_model

__all__ = [
    "Candidate",
    "Choice",
    "RepairModel",
    "RepairPlanner",
    "RepairProblem",
    "build_problem",
    "choose",
    "repair_model",
]
