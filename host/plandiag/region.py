"""Fault region identifier (paper 004 §4.3.1.5): where in the history a fault can have been.

From each symptom the identifier walks back along the causal links of the violated atom: gap
by gap and step by step, until the step whose action established the value the knowledge base
expected (that step is the start of the region, and is in it: it may not have established it
after all), an observation that saw the atom (it held its expected value then), or the
initial knowledge base. In that stretch a fault is a *suspect* when it can make the atom differ
from what the plan expected: an event that writes it, a fault mode whose effect on it differs
from its action's. A suspect's own precondition is followed back the same way (an event that
enables a fault mode is a suspect too). A step that reported failure or was halted makes all
its fault modes suspects. Steps in the region without a suspect are irrelevant: the inference
keeps them in the context tree as intended but does not expand them.

Sound, not complete: every diagnosis found over the suspects is a minimal diagnosis of the
whole history (its subsets are suspects too), but one that needs a fault outside the region
is not found. The pipeline then widens the search to the whole history.
"""

from __future__ import annotations

from dataclasses import dataclass

from host.plandiag.context import Context
from host.plandiag.interpret import Symptom
from host.plandiag.problem import HistoryProblem, bits, effective_delete, writes
from host.planning.task import GroundOp


@dataclass(frozen=True)
class Region:
    suspects: frozenset[int]
    first_point: int
    last_point: int
    steps: tuple[int, ...]  # the steps the region spans
    expanded: tuple[int, ...]  # those of them with a suspect fault mode
    atoms: frozenset[int]  # the atoms followed back

    def describe(self, problem: HistoryProblem) -> str:
        first_gap, last_gap = self.first_point // 2 + 1, (self.last_point + 1) // 2
        if not self.steps:
            span = f"the gaps before steps {first_gap}..{last_gap}"
        elif self.steps[0] == self.steps[-1]:
            span = f"step {self.steps[0]}"
        else:
            span = f"steps {self.steps[0]}..{self.steps[-1]}"
        if self.steps and first_gap <= last_gap and (first_gap, last_gap) != (
                self.steps[0] + 1, self.steps[-1]):
            span += f" (gaps before steps {first_gap}..{last_gap})"
        names = sorted(problem.atom_name(a) for a in self.atoms)
        following = f", following {', '.join(names[:6])}" if names else ""
        following += "" if len(names) <= 6 else f" and {len(names) - 6} more"
        skipped = len(self.steps) - len(self.expanded)
        return (f"fault region: {span}{following}; {len(self.suspects)} suspect fault(s), "
                f"{skipped} step(s) in it irrelevant and not expanded")


def _effect_on(op: GroundOp | None, a: int) -> int:
    if op is None:
        return 0
    if (op.add >> a) & 1:
        return 1
    return -1 if (effective_delete(op) >> a) & 1 else 0


def fault_region(ctx: Context, symptoms: list[Symptom]) -> Region:
    p = ctx.problem
    suspects: set[int] = set()
    seen: set[tuple[int, int]] = set()
    points: set[int] = set()
    steps: set[int] = set()
    work: list[tuple[int, int]] = []

    def suspect(fid: int, start_point: int) -> None:
        if fid not in suspects:
            suspects.add(fid)
            seen_there = {x for x, _, _ in ctx.observed.get(start_point, ())}
            work.extend((x >> 1, start_point) for x in p.faults[fid].op.pre
                        if x >> 1 not in seen_there)  # observed there: known, not suspected

    for sym in symptoms:
        points.add(sym.point)
        if sym.atom is not None:
            work.append((sym.atom, sym.point))
        else:
            steps.add(sym.step)
            for fid in p.steps[sym.step - 1].modes:
                suspect(fid, 2 * sym.step - 1)
    # the gaps share one list of ground events: index their writers by atom once
    writers: dict[int, list[int]] = {}
    for j, fid in enumerate(p.gaps[0] if p.gaps else ()):
        for a in bits(writes(p.faults[fid].op)):
            writers.setdefault(a, []).append(j)
    walked: dict[int, set[int]] = {}  # atom -> points whose transition was followed for it
    while work:
        a, point = work.pop()
        if (a, point) in seen:
            continue
        seen.add((a, point))
        done = walked.setdefault(a, set())
        q = point
        while q > 0 and q not in done:  # a walk that met an earlier one goes on as it did
            done.add(q)
            points.add(q)
            if q % 2:  # the gap that ends at q
                gap = p.gaps[q // 2]
                for j in writers.get(a, ()):
                    suspect(gap[j], q - 1)
            else:  # the step that ends at q
                spec = p.steps[q // 2 - 1]
                steps.add(spec.index)
                base = _effect_on(spec.nominal, a)
                for fid in spec.modes:
                    if _effect_on(p.faults[fid].op, a) != base:
                        suspect(fid, q - 1)
                if base:
                    points.add(q - 1)
                    break  # the step that established the expected value
            q -= 1
            if any(x == a for x, _, _ in ctx.observed.get(q, ())):
                break  # seen here: it held what was expected
    expanded = {p.faults[f].at for f in suspects if p.faults[f].mode_of is not None}
    region_steps = tuple(sorted(steps))
    return Region(frozenset(suspects), min(points, default=0), max(points, default=0),
                  region_steps, tuple(s for s in region_steps if s in expanded),
                  frozenset(a for a, _ in seen))
