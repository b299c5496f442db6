"""Plan a PDDL problem file as it is: the original system's repair problems.

The original TEDUSAR repair server wrote each diagnosis as a problem file (objects, the
initial state, the goal ``(and (good c) ...)``) and planned it with its domain.
``plan_problem_file(domain, problem)`` reads such a file with the ``pddl`` library, grounds
the domain over its objects (untyped objects are of type ``object``), takes the facts of
static predicates as static and the rest as the initial state, and runs the same planners
and validation as ``RepairPlanner``, returning a partially ordered ``Plan``. Nothing about a
robot model is known here, so no component is protected.

The original's files are not all clean PDDL, and each problem is named on one line with its
place: an unresolved git merge conflict (``<<<<<<<``), a syntax error (the library's line and
column), a problem written for another domain, an object the file uses but does not declare.
Facts of predicates the domain does not declare (``(component x)``, which some of the
original's problems carry for a domain without it) cannot matter to any action: they are left
out, and a note says which.
"""

from __future__ import annotations

import logging
from pathlib import Path
from typing import Any

from host.planning.domain import ROOT_TYPE, Domain, PddlAtom
from host.planning.errors import NoPlanError, ProblemError
from host.planning.grounding import ground
from host.planning.plan import Plan, deorder
from host.planning.planners import PLANNERS, unreachable, validate
from host.planning.search import DEFAULT_MAX_EXPANSIONS, SearchInput, relevant_ops

log = logging.getLogger(__name__)

CONFLICT_MARKERS = ("<<<<<<<", "=======", ">>>>>>>")


def _conflict_line(text: str) -> int | None:
    for n, line in enumerate(text.splitlines(), start=1):
        if line.startswith(CONFLICT_MARKERS):
            return n
    return None


def _terms(pred: Any) -> tuple[str, ...]:
    return tuple(str(t.name) for t in pred.terms)


def read_problem(domain: Domain, path: Path) -> tuple[dict[str, str], list[PddlAtom],
                                                      list[tuple[PddlAtom, bool]], list[str]]:
    """``(objects, init, goal literals, notes)`` of a problem file for ``domain``."""
    from pddl.logic import base, predicates
    from pddl.parser.problem import ProblemParser

    try:
        text = path.read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError) as exc:
        why = exc.strerror if isinstance(exc, OSError) else "not a UTF-8 text file"
        raise ProblemError(f"{path}: cannot read the problem ({why})",
                           "give a PDDL problem file") from exc
    conflict = _conflict_line(text)
    if conflict is not None:
        raise ProblemError(f"{path}:{conflict}: an unresolved git merge conflict",
                           "keep one side of the conflict and delete the <<<<<<< ======= "
                           ">>>>>>> lines")
    try:
        parsed = ProblemParser()(text)
    except Exception as exc:  # lark and the library's own errors alike
        first = str(exc).strip().splitlines()[0] if str(exc).strip() else type(exc).__name__
        raise ProblemError(f"{path}: not a valid PDDL problem: {first}",
                           "fix the PDDL syntax (the message names the line and column)") from exc
    if parsed.domain_name is not None and str(parsed.domain_name) != domain.name:
        raise ProblemError(
            f"{path}: the problem is for domain {parsed.domain_name}, {domain.path} defines "
            f"{domain.name}", "give the domain the problem was written for (--domain FILE)")
    objects: dict[str, str] = {}
    for obj in parsed.objects:
        tags = sorted(str(t) for t in obj.type_tags)
        objects[str(obj.name)] = tags[0] if tags else ROOT_TYPE
    known = set(domain.predicates)
    left_out: dict[str, None] = {}
    init: list[PddlAtom] = []

    def atom(pred: Any, where: str) -> PddlAtom:
        a = PddlAtom(str(pred.name), _terms(pred))
        missing = [x for x in a.args if x not in objects]
        if missing:
            raise ProblemError(f"{path}: {where} ({a.pred} {' '.join(a.args)}) names "
                               f"{missing[0]}, which :objects does not declare",
                               "declare every object the problem uses")
        return a

    for fact in parsed.init:
        if isinstance(fact, base.Not):
            continue  # closed world: a false fact is the absence of the atom
        if not isinstance(fact, predicates.Predicate):
            raise ProblemError(f"{path}: the initial fact {fact} is not supported",
                               "write plain atoms in :init")
        if str(fact.name) not in known:
            left_out.setdefault(str(fact.name))
            continue
        init.append(atom(fact, "the initial fact"))
    goal: list[tuple[PddlAtom, bool]] = []
    parts = parsed.goal.operands if isinstance(parsed.goal, base.And) else (parsed.goal,)
    for g in parts:
        positive = not isinstance(g, base.Not)
        inner = g if positive else g.argument
        if not isinstance(inner, predicates.Predicate):
            raise ProblemError(f"{path}: the goal {g} is not supported",
                               "write the goal as a conjunction of literals")
        if str(inner.name) not in known:
            raise ProblemError(f"{path}: the goal uses {inner.name}, which the domain does "
                               "not declare", "give the domain the problem was written for")
        goal.append((atom(inner, "the goal"), positive))
    notes = []
    if left_out:
        notes.append(f"left out the initial facts of {', '.join(left_out)}, which the domain "
                     "does not declare")
    return objects, init, goal, notes


def plan_problem_file(domain: Domain, path: Path, planner: str = "astar",
                      max_expansions: int = DEFAULT_MAX_EXPANSIONS) -> Plan:
    """A plan for the problem file ``path`` in ``domain``; raises ``NoPlanError``."""
    search = PLANNERS.get(planner)
    if search is None:
        raise ProblemError(f"unknown planner {planner!r}",
                           f"choose one of {', '.join(sorted(PLANNERS))}")
    objects, init_atoms, goal_atoms, notes = read_problem(domain, path)
    unknown = sorted({t for t in objects.values()} - {*domain.types, *domain.types.values(),
                                                       ROOT_TYPE})
    if unknown:
        raise ProblemError(f"{path}: objects of type(s) {', '.join(unknown)}, which the domain "
                           "does not declare", "declare them in the domain's (:types ...)")
    static = [a for a in init_atoms if a.pred in domain.statics]
    task = ground(domain, objects, static)
    init = task.state((a.pred, a.args) for a in init_atoms if a.pred not in domain.statics)
    goal = tuple(task.literal(a.pred, a.args, positive) for a, positive in goal_atoms)
    relevant = relevant_ops(task, init, goal)
    missing = unreachable(task, init, goal, relevant)
    if missing:
        raise NoPlanError(
            "no plan reaches the goal: " + ", ".join(task.describe(x) for x in missing[:6])
            + " cannot be reached", f"no action of {domain.path.name} can make it so",
            tuple(task.describe(x) for x in missing))
    pddl = path.read_text(encoding="utf-8") if planner == "fast-downward" else None
    result = search(SearchInput(task, init, goal, domain.path, pddl, max_expansions, relevant))
    if result.ops is None:
        raise NoPlanError("no plan reaches the goal: the actions needed interfere",
                          f"check the problem against {domain.path.name}")
    ops = [task.ops[i] for i in result.ops]
    validate(task, init, goal, ops, planner)
    log.debug("problem %s: %d steps", path, len(ops))
    return deorder(ops, sum(op.cost for op in ops), planner, notes)
