"""Diagnosis as planning: a history as a planning task for K* (the baseline of plandiag.py).

The task's plans are the alternative histories (after Sohrabi, Baier and McIlraith, "Diagnosis
as planning revisited"): the atoms of the history's ground task are nullary predicates, and a
chain of ``stage`` atoms walks through the history point by point. Before step ``i`` each
ground event of gap ``i`` has its own stage, left either by ``skip`` (cost 0) or by the event
(cost 1), in one fixed order, so a set of events is one plan and not one per ordering; then
the step's nominal action (cost 0) or one of its fault modes (cost 1) moves on to the next
gap. What was observed at a point is a precondition of every action that leaves it (and the
goal at the last point). A plan's cost is its number of faults, so K*'s top-quality search
with ``q=1`` lists every history of least cost: the minimum-cardinality diagnoses.

One difference from the engines' semantics: events of one gap happen here one after another
(an event's precondition sees the ones before it), there together; with the one or two faults
of the benchmark's histories that rarely matters, and the benchmark reports how often the
planner's answer equals SAT's.
"""

from __future__ import annotations

import tempfile
import time
from dataclasses import dataclass
from pathlib import Path

from host.plandiag.problem import HistoryProblem, bits, effective_delete
from host.planning.task import GroundOp


def _cond(pre_t: int, pre_f: int) -> list[str]:
    return [f"(a{a})" for a in bits(pre_t)] + [f"(not (a{a}))" for a in bits(pre_f)]


def _action(name: str, here: str, there: str, pre: list[str], op: GroundOp | None,
            cost: int) -> str:
    eff = [f"(not ({here}))", f"({there})"]
    if op is not None:
        eff += [f"(a{a})" for a in bits(op.add)]
        eff += [f"(not (a{a}))" for a in bits(effective_delete(op))]
    if cost:
        eff.append(f"(increase (total-cost) {cost})")
    return (f"  (:action {name}\n    :precondition (and ({here}) {' '.join(pre)})\n"
            f"    :effect (and {' '.join(eff)}))\n")


def encode(problem: HistoryProblem) -> tuple[str, str]:
    """The domain and problem text of ``problem`` as a planning task."""
    p = problem
    stages: list[str] = []
    actions: list[str] = []

    def stage() -> str:
        stages.append(f"s{len(stages)}")
        return stages[-1]

    def seen(point: int) -> list[str]:
        t, f = p.obs.get(point, (0, 0))
        return _cond(t, f)

    here = stage()
    if seen(0):
        there = stage()
        actions.append(_action("check-0", here, there, seen(0), None, 0))
        here = there
    for spec in p.steps:
        i = spec.index
        for j, fid in enumerate(p.gaps[i - 1]):
            there = stage()
            op = p.faults[fid].op
            actions.append(_action(f"skip-{i}-{j}", here, there, [], None, 0))
            actions.append(_action(f"f{fid}", here, there, _cond(op.pre_t, op.pre_f), op, 1))
            here = there
        if not spec.executed or 2 * i - 1 >= p.last_point:
            break
        there = stage()
        obs = seen(2 * i - 1)
        variants = [(f"f{f}", p.faults[f].op, 1) for f in spec.modes]
        if spec.nominal is not None:
            variants.append((f"nominal-{i}", spec.nominal, 0))
        for name, op, cost in variants:
            actions.append(_action(name, here, there, obs + _cond(op.pre_t, op.pre_f),
                                   op, cost))
        here = there
        obs_after = seen(2 * i)
        if obs_after:  # checked on leaving: a stage of its own keeps the step's arcs simple
            there = stage()
            actions.append(_action(f"check-{i}", here, there, obs_after, None, 0))
            here = there
    goal = seen(p.last_point) if p.last_point % 2 else []
    atoms = len(p.task.atoms)
    preds = " ".join(f"(a{a})" for a in range(atoms)) + " " + " ".join(f"({s})" for s in stages)
    domain = ("(define (domain history)\n"
              "  (:requirements :strips :negative-preconditions :action-costs)\n"
              f"  (:predicates {preds})\n  (:functions (total-cost) - number)\n"
              + "".join(actions) + ")\n")
    init = " ".join([f"(a{a})" for a in bits(p.init)] + [f"({stages[0]})", "(= (total-cost) 0)"])
    task = (f"(define (problem h) (:domain history)\n  (:init {init})\n"
            f"  (:goal (and ({here}) {' '.join(goal)}))\n  (:metric minimize (total-cost)))\n")
    return domain, task


@dataclass
class PlannerRun:
    diagnoses: set[frozenset[int]]
    seconds: float
    timed_out: bool


_SYMMETRIES = ("sym=structural_symmetries(time_bound=0,search_symmetries=oss,"
               "stabilize_initial_state=false,keep_operator_symmetries=true)")


def minimum_diagnoses(problem: HistoryProblem, timeout_s: int) -> PlannerRun:
    """Every least-cost alternative history by K*'s top-quality search (q=1, the search of
    ``kstar_planner.planners.plan_topq``), wall time of encoding, writing and the planner's
    subprocess. The translator's invariant synthesis is switched off: on these tasks of
    nullary atoms it takes minutes and finds nothing the search needs."""
    from kstar_planner import planners  # type: ignore[import-untyped]

    start = time.perf_counter()
    domain, task = encode(problem)
    with tempfile.TemporaryDirectory() as tmp:
        dfile, pfile = Path(tmp) / "domain.pddl", Path(tmp) / "problem.pddl"
        dfile.write_text(domain)
        pfile.write_text(task)
        data = planners.run_planner([
            "--overall-time-limit", f"{timeout_s}s", str(dfile), str(pfile),
            "--translate-options", "--invariant-generation-max-candidates", "0",
            "--search-options", "--symmetries", _SYMMETRIES, "--search",
            "kstar(lmcut(transform=undo_to_origin()), q=1.0, find_unordered_plans=false, "
            "dump_plan_files=false, json_file_to_dump=PLANS_JSON_NAME, symmetries=sym)"])
    seconds = time.perf_counter() - start
    found: set[frozenset[int]] = set()
    for plan in data.get("plans", []):
        names = [a.strip().strip("()").split()[0] for a in plan["actions"]]
        found.add(frozenset(int(n[1:]) for n in names if n[0] == "f"))
    return PlannerRun(found, seconds, bool(data.get("timeout_triggered")))
