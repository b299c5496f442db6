"""The inference problem both engines solve: a history compiled to bit masks, and its semantics.

A ``HistoryProblem`` is what the context & plan interpreter (``context.py``) makes of a history: the
initial state (an ``int`` whose bit ``a`` is atom ``a``, as in ``host.planning.task``), one
``StepSpec`` per step (the nominal ground action, or None when it cannot have run as intended,
and the fault modes that may replace it), the candidate exogenous events of every gap, every
``Fault`` with its prior, and the observations as masks per *point*. Points number the states
of the history: point 0 is the initial knowledge base; gap ``i`` (the time before step ``i``)
leads from point ``2i-2`` to ``2i-1``, where step ``i``'s precondition check looks; step ``i``
leads on to point ``2i``, its expected-state check (``during`` observations look there too).

The semantics, which the context tree, the SAT encoding and naive enumeration share (and the
tests hold them to): a *diagnosis* is a set of faults. Its history runs every step as its mode
if the set holds one for it, else as its nominal action (there must be one), and in every gap
exactly the set's events of that gap, all at once: each event's precondition holds before the
gap, no event adds an atom another deletes, and the state after is ``(s - deletes) | adds``.
Every variant's precondition must hold where it runs (STRIPS: deletes first, then adds), and
every observation must hold at its point. A diagnosis is *minimal* when no proper subset of it
is one. ``simulate`` runs a fault set and says where it fails.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable, Sequence
from dataclasses import dataclass, field
from enum import StrEnum

from host.plandiag.model import FaultKind
from host.planning.task import GroundOp, Task


class Stop(StrEnum):
    """Why a simulated history fails."""

    NO_VARIANT = "the step cannot have run as intended"
    PRECONDITION = "a precondition is false"
    CONFLICT = "two events in one gap contradict each other"
    OBSERVATION = "an observation contradicts it"


@dataclass(frozen=True)
class Fault:
    """One fault mode at one step, or one exogenous event in one gap."""

    id: int
    kind: FaultKind
    at: int  # the step (mode) or the gap (event), from 1; gap i comes before step i
    op: GroundOp
    prior: float
    mode_of: str | None = None
    components: tuple[str, ...] = ()

    def label(self) -> str:
        where = f"at step {self.at}" if self.kind is FaultKind.MODE else f"before step {self.at}"
        return f"{self.action()} {where}"

    def action(self) -> str:
        return op_label(self.op)


@dataclass(frozen=True)
class StepSpec:
    index: int
    label: str
    nominal: GroundOp | None
    modes: tuple[int, ...]
    executed: bool = True


@dataclass
class HistoryProblem:
    task: Task
    init: int
    steps: list[StepSpec]
    gaps: list[tuple[int, ...]]  # gaps[i - 1]: the events that may happen before step i
    faults: list[Fault]
    obs: dict[int, tuple[int, int]]  # point -> (atoms observed true, atoms observed false)
    last_point: int = 0
    notes: list[str] = field(default_factory=list)

    def describe_state(self, state: int, atoms: Iterable[int]) -> list[str]:
        out = []
        for a in sorted(atoms):
            pred, args = self.task.atoms[a]
            text = f"{pred}({','.join(args)})"
            out.append(text if (state >> a) & 1 else "~" + text)
        return out

    def atom_name(self, a: int) -> str:
        pred, args = self.task.atoms[a]
        return f"{pred}({','.join(args)})"

    def obs_ok(self, point: int, state: int) -> bool:
        o = self.obs.get(point)
        return o is None or ((state & o[0]) == o[0] and not (state & o[1]))

    def impossible_step(self, universe: frozenset[int] | None) -> int | None:
        """A step that ran but can have run in no way at all (no nominal action, no fault
        mode in ``universe``): then no diagnosis exists. None when there is none."""
        for spec in self.steps:
            if spec.executed and spec.nominal is None and not any(
                    universe is None or f in universe for f in spec.modes):
                return spec.index
        return None


def bits(mask: int) -> list[int]:
    """The atoms (bit positions) set in ``mask``, lowest first."""
    out = []
    while mask:
        low = mask & -mask
        out.append(low.bit_length() - 1)
        mask ^= low
    return out


def op_label(op: GroundOp) -> str:
    return f"{op.name}({','.join(op.args)})"


def effective_delete(op: GroundOp) -> int:
    """The atoms ``op`` makes false (an atom both added and deleted ends true)."""
    return op.delete & ~op.add


def writes(op: GroundOp) -> int:
    return op.add | op.delete


def apply_events(state: int, ops: Sequence[GroundOp]) -> int | None:
    """The state after the events ``ops`` happen together in one gap; None if one is not
    applicable or two conflict."""
    add = dele = 0
    for op in ops:
        if not op.applicable(state):
            return None
        d = effective_delete(op)
        if (op.add & dele) or (d & add):
            return None
        add |= op.add
        dele |= d
    return (state & ~dele) | add


def conflict(a: GroundOp, b: GroundOp) -> bool:
    return bool((a.add & effective_delete(b)) or (b.add & effective_delete(a)))


def live_atoms(problem: HistoryProblem, allowed: Callable[[int], bool]) -> list[int]:
    """``live[p]``: the atoms whose value at point ``p`` may still matter — read later by an
    observation or by the precondition of a variant or event that may run (the faults
    ``allowed``), before every variant that may run overwrites it alike. An event that writes
    no live atom after its gap is in no minimal diagnosis: without it, the history differs
    only in atoms nothing reads before they are overwritten, so it stays consistent."""
    last = problem.last_point
    live = [0] * (last + 1)

    def seen(q: int) -> int:
        t, f = problem.obs.get(q, (0, 0))
        return t | f

    gap_reads: dict[tuple[int, ...], int] = {}
    cur = live[last] = seen(last)
    for q in range(last, 0, -1):
        if q % 2:  # the gap that ends at q
            gap = tuple(f for f in problem.gaps[q // 2] if allowed(f))
            read = gap_reads.get(gap)
            if read is None:
                read = 0
                for f in gap:
                    op = problem.faults[f].op
                    read |= op.pre_t | op.pre_f
                gap_reads[gap] = read
            cur |= read
        else:  # the step that ends at q
            spec = problem.steps[q // 2 - 1]
            ops = [problem.faults[f].op for f in spec.modes if allowed(f)]
            if spec.nominal is not None:
                ops.append(spec.nominal)
            kill_add = kill_del = -1
            read = 0
            for op in ops:
                kill_add &= op.add
                kill_del &= effective_delete(op)
                read |= op.pre_t | op.pre_f
            kill = (kill_add | kill_del) if ops else 0
            cur = (cur & ~kill) | read
        cur |= seen(q - 1)
        live[q - 1] = cur
    return live


@dataclass
class SimulatedRun:
    """A simulated history: the state at every point reached, and where it failed (if so)."""

    states: list[int]
    stop: Stop | None = None
    stop_point: int = -1
    detail: str = ""

    @property
    def consistent(self) -> bool:
        return self.stop is None


def simulate(problem: HistoryProblem, faults: Iterable[int], start: int = 1,
             rejoin: Sequence[int] | None = None, rejoin_at: int = 0) -> SimulatedRun:
    """Run the history with the fault set ``faults``.

    ``rejoin`` (the states of a consistent run, point by point) lets a caller check a fault
    set that differs from that run's only from step ``start`` on: the run starts from
    ``rejoin``'s state before gap ``start``, and ends as consistent at the first point from
    ``rejoin_at`` on where its state is the one ``rejoin`` had there (the rest is the same).
    """
    modes: dict[int, Fault] = {}
    events: dict[int, list[GroundOp]] = {}
    for fid in faults:
        f = problem.faults[fid]
        if f.kind is FaultKind.MODE:
            if f.at in modes:
                return SimulatedRun([problem.init], Stop.NO_VARIANT, 2 * f.at,
                           f"two modes at step {f.at}")
            modes[f.at] = f
        else:
            events.setdefault(f.at, []).append(f.op)
    state = problem.init if rejoin is None else rejoin[2 * start - 2]
    run = SimulatedRun([state])
    if start == 1 and not problem.obs_ok(0, state):
        return _fail(run, problem, 0, Stop.OBSERVATION)
    for spec in problem.steps[start - 1 :]:
        i = spec.index
        nxt = apply_events(state, events.get(i, ()))
        if nxt is None:
            run.states.append(state)
            return _fail(run, problem, 2 * i - 1, Stop.CONFLICT)
        state = nxt
        run.states.append(state)
        if not problem.obs_ok(2 * i - 1, state):
            return _fail(run, problem, 2 * i - 1, Stop.OBSERVATION)
        if not spec.executed:
            break
        if rejoin is not None and 2 * i - 1 >= rejoin_at and rejoin[2 * i - 1] == state:
            return run
        op = modes[i].op if i in modes else spec.nominal
        if op is None:
            run.states.append(state)
            return _fail(run, problem, 2 * i, Stop.NO_VARIANT, spec.label)
        if not op.applicable(state):
            run.states.append(state)
            return _fail(run, problem, 2 * i, Stop.PRECONDITION, op_label(op))
        state = op.apply(state)
        run.states.append(state)
        if not problem.obs_ok(2 * i, state):
            return _fail(run, problem, 2 * i, Stop.OBSERVATION)
        if rejoin is not None and 2 * i >= rejoin_at and rejoin[2 * i] == state:
            return run
    return run


def _fail(run: SimulatedRun, problem: HistoryProblem, point: int, stop: Stop,
          detail: str = "") -> SimulatedRun:
    run.stop, run.stop_point = stop, point
    if stop is Stop.OBSERVATION:
        t, f = problem.obs[point]
        state = run.states[-1]
        wrong = [a for a in range(len(problem.task.atoms))
                 if ((t >> a) & 1 and not (state >> a) & 1) or ((f >> a) & 1 and (state >> a) & 1)]
        detail = ", ".join(("~" if (t >> a) & 1 else "") + problem.atom_name(a) for a in wrong)
        detail = f"it predicts {detail}" if detail else detail
    run.detail = detail
    return run
