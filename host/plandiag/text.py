"""An explanation as a person reads it: what went wrong, and the winning path through the tree.

``render`` writes the alarm, the symptoms (local or propagated), the fault region, the minimal
alternative histories (histories that differ only in the gap one event happened in are shown
as one line: "door-closes(door1) between steps 3 and 13"), then the most probable history as
its path through the context tree: runs of steps that went as intended, each event and fault
mode with what it changed, the alarm step, and for every fault why the history cannot do
without it (the contradiction that remains when it is left out). Then the class of the fault
and the corrected knowledge base; or, when nothing explains the alarm, the plan error and the
conditions the domain may lack.
"""

from __future__ import annotations

from collections.abc import Iterable

from host.plandiag.history import Where
from host.plandiag.model import FaultKind
from host.plandiag.pipeline import Explanation
from host.plandiag.problem import Fault, HistoryProblem, Stop, simulate
from host.plandiag.result import AlternativeHistory

MAX_LISTED = 10
MAX_CHECKS = 4
_WHERE = {Where.PRE: "at its precondition check", Where.DURING: "while it ran",
          Where.POST: "at its expected-state check"}


def render(e: Explanation) -> list[str]:
    p = e.context.problem
    a = e.alarm.alarm
    out = [f"alarm: step {a.step} {p.steps[a.step - 1].label}, {_WHERE[a.where]}"
           + (" (critical: the step was halted at once)" if a.critical and a.where is Where.DURING
              else "") + (f": {a.message}" if a.message else "")]
    if e.alarm.dropped_steps:
        out.append(f"  ({e.alarm.dropped_steps} step(s) recorded after the alarm left out)")
    out.append("symptoms:" if e.symptoms else "symptoms: none (every observation as expected)")
    out += [f"  {s.kind.value}: {s.text}" for s in e.symptoms]
    if e.suspicion.cleared:
        out.append("out of suspicion (layer 0 shows their components working): "
                   + ", ".join(sorted(e.suspicion.cleared)))
    if e.region is not None:
        out.append(e.region.describe(p))
        if e.widened:
            out.append("  nothing in the region explains the alarm: searched the whole history")
    o = e.outcome
    state = "complete" if o.complete else f"incomplete: the {o.cut_by} bound cut the list"
    if e.histories:
        out.append(f"{len(e.histories)} minimal alternative histor"
                   f"{'y' if len(e.histories) == 1 else 'ies'} ({state}; engine {e.engine}, "
                   f"{o.elapsed_s * 1000:.1f} ms):")
        out += [f"  {line}" for line in listing(e.histories)]
        best = e.histories[0]
        out.append("the most probable history, along the context tree:")
        out += [f"  {line}" for line in winning_path(e, best)]
        out.append("class: " + ", ".join(c.value for c in e.classes()))
        if e.kb is not None:
            out += _kb_lines(e)
        return out
    pe = e.plan_error
    proven = not o.explainable
    out.append("no alternative history explains the alarm"
               + (" (proven: no fault mode or event, in any combination)" if proven
                  else f" ({state})"))
    if pe is not None:
        out.append(f"class: plan error at step {pe.step} {pe.label}: {pe.reason}")
        if pe.conditions:
            out.append(f"  a precondition the domain may lack, from what held at step {pe.step}:")
            for c in pe.conditions:
                why = (f"held at the earlier successful run(s) at step(s) "
                       f"{', '.join(map(str, c.supported_by))}" if c.supported_by
                       else "no earlier run to compare with")
                out.append(f"    {c.literal}   ({c.ground} at step {pe.step}; {why})")
        elif p.steps[pe.step - 1].executed:
            out.append("  no condition over the action's arguments separates this run from the "
                       "earlier successful ones")
    return out


def _gaps_text(gaps: list[int]) -> str:
    gaps = sorted(gaps)
    if len(gaps) > 1 and gaps == list(range(gaps[0], gaps[-1] + 1)):
        return f"between steps {gaps[0] - 1} and {gaps[-1]} (in one of {len(gaps)} gaps)"
    return "before step " + ", ".join(map(str, gaps))


def listing(histories: list[AlternativeHistory]) -> list[str]:
    """One line per history, or per group of one-event histories that differ in the gap."""
    groups: dict[str, list[AlternativeHistory]] = {}
    order: list[str] = []
    for h in histories:
        f = h.faults[0].fault if h.cardinality == 1 else None
        key = f"event {f.action()}" if f is not None and f.kind is FaultKind.EVENT else \
            f"history {id(h)}"
        if key not in groups:
            order.append(key)
        groups.setdefault(key, []).append(h)
    lines = []
    for n, key in enumerate(order, start=1):
        hs = groups[key]
        if n > MAX_LISTED:
            lines.append(f"... and {len(order) - MAX_LISTED} more (--json lists them all)")
            break
        if len(hs) == 1:
            lines.append(f"{n}. p={hs[0].probability:.3f}  {hs[0].summary()}")
            continue
        c = hs[0].faults[0]
        total = sum(h.probability for h in hs)
        lines.append(f"{n}. p={total:.3f}  {c.cls.value}: {c.fault.action()} "
                     f"{_gaps_text([h.faults[0].fault.at for h in hs])}, "
                     f"p={hs[0].probability:.3f} each")
    return lines


def _changes(p: HistoryProblem, before: int, after: int) -> str:
    diff = before ^ after
    lits = [("" if (after >> a) & 1 else "~") + p.atom_name(a)
            for a in range(len(p.task.atoms)) if (diff >> a) & 1]
    return ", ".join(lits) if lits else "no change"


def _checks(p: HistoryProblem, points: Iterable[int]) -> str:
    lits = []
    for q in points:
        t, f = p.obs.get(q, (0, 0))
        lits += [p.atom_name(a) for a in range(len(p.task.atoms)) if (t >> a) & 1]
        lits += ["~" + p.atom_name(a) for a in range(len(p.task.atoms)) if (f >> a) & 1]
    if not lits:
        return ""
    shown = ", ".join(lits[:MAX_CHECKS]) + (f" and {len(lits) - MAX_CHECKS} more"
                                             if len(lits) > MAX_CHECKS else "")
    return f" (observed {shown}, as predicted)"


def winning_path(e: Explanation, best: AlternativeHistory) -> list[str]:
    p = e.context.problem
    run = simulate(p, best.ids)
    states = run.states
    events: dict[int, list[Fault]] = {}
    modes: dict[int, Fault] = {}
    for c in best.faults:
        if c.fault.kind is FaultKind.EVENT:
            events.setdefault(c.fault.at, []).append(c.fault)
        else:
            modes[c.fault.at] = c.fault
    lines: list[str] = []
    run_from: int | None = None

    def flush(upto: int) -> None:
        nonlocal run_from
        if run_from is not None:
            span = f"step {run_from}" if run_from == upto else f"steps {run_from}..{upto}"
            pts = range(2 * run_from - 1, 2 * upto + 1)
            lines.append(f"{span}: as intended{_checks(p, pts)}")
        run_from = None

    for spec in p.steps:
        i = spec.index
        pre, post = 2 * i - 1, 2 * i
        if i in events:
            flush(i - 1)
            for f in events[i]:
                lines.append(f"before step {i}: {f.action()} happened: "
                             f"{_changes(p, states[pre - 1], states[pre])}")
        if not spec.executed or pre >= p.last_point:
            flush(i - 1)
            lines.append(f"step {i} {spec.label}: not dispatched, its precondition check "
                         f"saw what this history predicts{_checks(p, [pre])}")
            break
        if i in modes:
            flush(i - 1)
            f = modes[i]
            meant = (f"instead of {_changes(p, states[pre], spec.nominal.apply(states[pre]))}"
                     if spec.nominal is not None and spec.nominal.applicable(states[pre])
                     else "it could not run as intended")
            lines.append(f"step {i} {spec.label}: ran as {f.action()}: "
                         f"{_changes(p, states[pre], states[post])} ({meant})"
                         f"{_checks(p, [pre, post])}")
        elif run_from is None:
            run_from = i
        if post >= p.last_point:
            flush(i)
    for c in best.faults:
        lines.append(f"without {c.fault.label()}: " + _why(p, best.ids - {c.fault.id}))
    return lines


def _why(p: HistoryProblem, faults: frozenset[int]) -> str:
    run = simulate(p, faults)
    if run.consistent:  # pragma: no cover - a minimal diagnosis needs each of its faults
        return "the history would be consistent too"
    q = run.stop_point
    i = (q + 1) // 2
    if run.stop is Stop.OBSERVATION:
        where = "precondition check" if q % 2 else "expected-state check"
        return f"step {i}'s {where} contradicts the observations: {run.detail}"
    if run.stop is Stop.PRECONDITION:
        return f"step {i} cannot run: a precondition of {run.detail} is false"
    if run.stop is Stop.CONFLICT:
        return f"the events before step {i} contradict each other"
    return f"step {i} cannot have run as reported ({run.detail})"


def _kb_lines(e: Explanation) -> list[str]:
    kb = e.kb
    assert kb is not None
    lines = []
    if kb.observed:
        lines.append("knowledge base: the observations at the alarm already changed "
                     + ", ".join(kb.observed))
    inferred = kb.changes()
    if inferred:
        certain = set(kb.certain)
        lines.append("knowledge base corrected (most probable history): " + ", ".join(
            x + ("" if x in certain else " (probable)") for x in inferred))
    else:
        lines.append("knowledge base: nothing more to correct: the most probable history "
                     "agrees with it")
    return lines

