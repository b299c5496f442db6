"""One incremental SAT solver holding a theory: the shared state every search algorithm uses.

``SatContext`` loads a ``Theory``'s encoding (``encoding.py``: one variable per atom, the
clauses as numbers, the circuit structure; built here unless the caller has it, e.g. from the
model cache) into an incremental PySAT solver. Observations are never added as clauses: they
are passed as *assumptions* on each call, so a changed observation needs no rebuilding. A
search may add clauses that hold for one run only by guarding them with a fresh activation
variable (``new_run()``/``end_run()``): the run assumes it, and ``end_run`` disables the clauses for
good with a unit clause; the variable stays, so after ``RENEW_AFTER`` runs ``renew()`` (the
diagnoser calls it between runs) starts a fresh solver. Cardinality bounds over the health
variables come from an incremental totalizer (``pysat.card.ITotalizer``) grown on demand. A
wall-clock budget interrupts a running solver call (``solve`` then returns None); the budget
is the only clock this package reads, and only to bound computation time.
"""

from __future__ import annotations

import math
import threading
import time
from collections.abc import Callable, Iterable, Iterator
from contextlib import contextmanager
from typing import Any

from pysat.card import ITotalizer  # type: ignore[import-untyped]
from pysat.formula import WCNF  # type: ignore[import-untyped]
from pysat.solvers import Solver  # type: ignore[import-untyped]

import host.diagnosis.sigint  # noqa: F401  (PySAT leaves SIGINT to the process)
from host.diagnosis.encoding import Encoding, encode
from host.diagnosis.logic import Literal, Theory, ab
from host.diagnosis.quota import Quota
from host.diagnosis.result import Bound, SearchOutcome
from host.diagnosis.structure import Structure


class _Watchdog:
    """One thread per context that interrupts the solver when the armed deadline passes
    (starting a thread per call would cost more than a small diagnosis). Arming and disarming
    wake the thread only when it must wait less than it does: a wake-up hands the GIL over and
    back, which cost a small diagnosis (c432, k = 1) a third of its time. A thread asleep until
    an old deadline wakes then, finds the new one (or none) and sleeps again. Idle, the thread
    wakes every ``IDLE_POLL_S`` for ``IDLE_FOR_S`` after a run (then sleeps until notified): a
    run armed meanwhile with a budget longer than that needs no wake-up (diagnoses in a row,
    as a daemon's burst or a benchmark makes them, 0.1-0.2 ms each on c432)."""

    IDLE_POLL_S = 0.25
    IDLE_FOR_S = 5.0

    def __init__(self, solver: Any) -> None:
        self._solver = solver  # anything with ``interrupt()``: the context's solvers
        self._target: Any = solver  # what gets interrupted: the solvers, or a MaxSAT run
        self._cv = threading.Condition()
        self._deadline: float | None = None
        self._closed = False
        self._thread: threading.Thread | None = None
        self._sleeps_until = math.inf  # when the thread wakes by itself (inf: when notified)

    def arm(self, deadline: float) -> None:
        with self._cv:
            self._deadline = deadline
            if self._thread is None:
                self._thread = threading.Thread(target=self._run, daemon=True,
                                                name="diagnosis-watchdog")
                self._thread.start()
            if deadline < self._sleeps_until:
                self._cv.notify()

    def retarget(self, target: Any) -> None:
        """Interrupt ``target`` (anything with ``interrupt()``; None: the solver) from now on."""
        with self._cv:
            self._target = self._solver if target is None else target

    def disarm(self) -> None:
        with self._cv:  # after this no interrupt can come for the finished run
            self._deadline = None

    def close(self) -> None:
        with self._cv:
            self._closed = True
            self._cv.notify()
        if self._thread is not None:
            self._thread.join()

    def _run(self) -> None:
        idle_since = time.perf_counter()
        with self._cv:
            while not self._closed:
                if self._deadline is None:
                    now = time.perf_counter()
                    idle_since = min(idle_since, now)
                    if now - idle_since >= self.IDLE_FOR_S:
                        self._sleeps_until = math.inf
                        self._cv.wait()
                        idle_since = time.perf_counter()
                    else:
                        self._sleeps_until = now + self.IDLE_POLL_S
                        self._cv.wait(self.IDLE_POLL_S)
                    continue
                idle_since = math.inf  # armed: the idle time starts when it is disarmed
                remaining = self._deadline - time.perf_counter()
                if remaining <= 0:
                    self._target.interrupt()
                    self._deadline = None
                else:
                    self._sleeps_until = self._deadline
                    self._cv.wait(remaining)


def maxsat_formula(hard: list[list[int]], soft: list[int], nv: int) -> WCNF:
    """A MaxSAT formula of the clauses ``hard`` (shared, not copied: RC2 and the solvers
    copy what they keep) and one soft unit clause of weight 1 per literal of ``soft``, over
    variables up to ``nv``, which must be the largest variable of the clauses, no more: RC2
    numbers its own variables from there, and the solver decides on every variable up to
    the largest (the context's ``top``, runs and totalizer included, made c6288 2x slower).
    What ``WCNF.append`` per clause builds, without its per-clause work (c7552: 30 ms of
    Python for 13,000 clauses, more than RC2's search)."""
    wcnf = WCNF()
    wcnf.hard = list(hard)
    wcnf.soft = [[lit] for lit in soft]
    wcnf.wght = [1] * len(soft)
    wcnf.topw = len(soft) + 1
    wcnf.nv = max(nv, max((abs(x) for x in soft), default=0))
    return wcnf


class SatContext:
    #: runs (activation variables, ``new_run``) after which ``renew`` starts a fresh solver
    RENEW_AFTER = 20_000

    def __init__(self, theory: Theory, solver: str = "g4",
                 encoding: Encoding | None = None) -> None:
        """``encoding``: ``theory``'s (``encode(theory)``), when the caller has it already."""
        if encoding is None:
            encoding = encode(theory)
        elif encoding.theory is not theory and encoding.theory != theory:
            raise ValueError("the encoding is of another theory")
        self.theory = theory
        self.encoding = encoding
        self.vars: dict[str, int] = dict(encoding.vars)  # grows: the encoding's stays as is
        self.top = len(self.vars)
        self._solver_name = solver
        self.solver = Solver(name=solver)
        # CaDiCaL in PySAT cannot be interrupted: budgets are then checked between calls only
        self._interruptible = not solver.startswith(("cd", "cadical"))
        self.ab_vars: list[int] = [self.vars[ab(c)] for c in theory.components]
        self.index_of_ab = {v: i for i, v in enumerate(self.ab_vars)}
        self.solver.append_formula(encoding.clauses)
        self._tot: ITotalizer | None = None
        self._deadline: float | None = None
        self._wcnf: WCNF | None = None  # ``health_wcnf``
        self._plain: Solver | None = None  # the theory's clauses only (``solve_plain``)
        self._last: Solver = self.solver  # the solver of the last call (its core, its model)
        self._watchdog = _Watchdog(self)
        self.calls = 0
        self.runs = 0  # since the solver was made
        self.renewed = 0
        self._atom_of: dict[int, str] | None = None

    def renew(self) -> bool:
        """Start a fresh solver once ``RENEW_AFTER`` runs have used it; True when it did.
        A solver never frees a variable: each run's activation literal (``new_run``) stays in
        it for good, fixed false, so a daemon diagnosing for weeks would grow by one variable a
        run without bound (about 200 bytes each). The atoms keep their numbers (observations
        assumed as solver literals stay valid); learnt clauses and the totalizer are dropped
        and come back as needed. Call it between runs, never inside one."""
        if self.runs < self.RENEW_AFTER:
            return False
        self.stop_budget()
        old, self.solver = self.solver, Solver(name=self._solver_name)
        self.top = max(self.vars.values(), default=0)
        self.solver.append_formula(self.encoding.clauses)
        if self._tot is not None:
            self._tot.delete()
            self._tot = None
        self._watchdog.close()
        self._watchdog = _Watchdog(self)
        self._last = self.solver
        old.delete()
        self.runs = 0
        self.renewed += 1
        return True

    # -- variables -------------------------------------------------------------------------
    def var(self, atom: str) -> int:
        v = self.vars.get(atom)
        if v is None:
            self.top += 1
            v = self.vars[atom] = self.top
        return v

    def new_var(self) -> int:
        self.top += 1
        return self.top

    def lit(self, literal: Literal) -> int:
        v = self.var(literal.atom)
        return v if literal.positive else -v

    def atom_of(self, lit: int) -> str | None:
        """The atom of a solver literal (None for auxiliary variables)."""
        if self._atom_of is None or len(self._atom_of) != len(self.vars):
            self._atom_of = {v: a for a, v in self.vars.items()}
        return self._atom_of.get(abs(lit))

    def health_wcnf(self) -> WCNF:
        """The theory as a MaxSAT formula (hard: its clauses; soft: each component healthy,
        weight 1), built once; callers add the observations to their solver, not to it."""
        if self._wcnf is None:
            self._wcnf = maxsat_formula(self.encoding.clauses, [-v for v in self.ab_vars],
                                        len(self.encoding.vars))
        return self._wcnf

    def structure(self) -> Structure | None:
        """The theory's circuit structure (``structure.infer_structure``), inferred once."""
        return self.encoding.structure()

    # -- runs, bounds and budget -----------------------------------------------------------
    def new_run(self) -> int:
        """A fresh activation literal for clauses that hold during one run only."""
        self.runs += 1
        return self.new_var()

    def end_run(self, act: int) -> None:
        self.solver.add_clause([-act])

    def at_most(self, k: int) -> list[int]:
        """Assumptions that allow at most ``k`` abnormal components."""
        n = len(self.ab_vars)
        if k >= n:
            return []
        if self._tot is None:
            self._tot = ITotalizer(lits=self.ab_vars, ubound=min(n, k + 2), top_id=self.top)
            self.solver.append_formula(self._tot.cnf.clauses)
            if self._plain is None:  # the theory alone, for ``solve_plain``
                self._plain = Solver(name=self._solver_name, bootstrap_with=self.encoding.clauses)
            self.top = max(self.top, self._tot.top_id)
        elif len(self._tot.rhs) <= k:
            self._tot.increase(ubound=min(n, 2 * k + 1), top_id=self.top)
            if self._tot.nof_new:
                self.solver.append_formula(self._tot.cnf.clauses[-self._tot.nof_new :])
            self.top = max(self.top, self._tot.top_id)
        return [-self._tot.rhs[k]]

    def start_budget(self, seconds: float | None) -> None:
        self.stop_budget()
        if seconds is None:
            return
        self._deadline = time.perf_counter() + seconds
        if self._interruptible:
            self._watchdog.arm(self._deadline)

    def stop_budget(self) -> None:
        if self._deadline is not None and self._interruptible:
            self._watchdog.disarm()
            self.solver.clear_interrupt()
            if self._plain is not None:
                self._plain.clear_interrupt()
        self._deadline = None

    @contextmanager
    def interrupting(self, target: Any) -> Iterator[None]:
        """While inside, the budget interrupts ``target`` (e.g. an RC2 run) instead."""
        self._watchdog.retarget(target)
        try:
            yield
        finally:
            self._watchdog.retarget(None)

    def remaining(self) -> float | None:
        """Seconds left of the budget (None: no budget)."""
        return None if self._deadline is None else self._deadline - time.perf_counter()

    def out_of_time(self) -> bool:
        return self._deadline is not None and time.perf_counter() >= self._deadline

    # -- calls -----------------------------------------------------------------------------
    def solve(self, assumptions: list[int]) -> bool | None:
        """SAT under ``assumptions``; None when the time budget ran out."""
        return self._solve_on(self.solver, assumptions)

    def solve_plain(self, assumptions: list[int]) -> bool | None:
        """SAT of the theory alone (no run's clauses, no cardinality bound) under
        ``assumptions``, which name no run's variable: on the solver itself until it holds a
        totalizer, then on a second solver holding the theory's clauses only, made with the
        totalizer (so that the run that needs a bound pays for it, not the next level 1's
        few propagations). Every variable of the totalizer is a decision of every call
        (c880, the checks of level 1 after a level-2 run: 0.66 ms a call against 0.02 ms)."""
        return self._solve_on(self.solver if self._plain is None else self._plain, assumptions)

    def _solve_on(self, solver: Solver, assumptions: list[int]) -> bool | None:
        self.calls += 1
        self._last = solver
        if self._deadline is None or not self._interruptible:
            if self.out_of_time():
                return None
            return bool(solver.solve(assumptions=assumptions))
        if self.out_of_time():
            return None
        result = solver.solve_limited(assumptions=assumptions, expect_interrupt=True)
        return None if result is None else bool(result)

    def interrupt(self) -> None:
        """Stop the running call (the budget's watchdog calls it from its thread)."""
        self.solver.interrupt()
        if self._plain is not None:
            self._plain.interrupt()

    def more_than(self, assumptions: list[int], found: list[frozenset[int]]) -> bool | None:
        """Is there a diagnosis under ``assumptions`` other than ``found`` (and their
        supersets)? None when the time budget ran out."""
        act = self.new_run()
        try:
            for bad in found:
                self.solver.add_clause([-self.ab_vars[i] for i in bad] + [-act])
            return self.solve([*assumptions, act])
        finally:
            self.end_run(act)

    def list_diagnoses(self, assumptions: list[int], act: int, out: SearchOutcome,
                       quota: Quota, k: int,
                       expand: Callable[[frozenset[int]], Iterable[frozenset[int]]] | None
                       = None) -> bool:
        """Add every diagnosis (of size ``k``) the solver finds under ``assumptions`` to
        ``out``, each blocked for the rest of the run ``act``; False when a bound (count,
        time) cut the listing. ``expand`` may name more of the same size for each one found
        (plan diagnosis: the same event in another gap): those that are no superset of one
        listed are listed and blocked too, and the solver need not find them."""
        while True:
            if quota.reached(k):
                out.cut_by = Bound.MAX_COUNT
                return False
            r = self.solve(assumptions)
            if r is None:
                out.cut_by = Bound.TIME_BUDGET
                return False
            if not r:
                return True
            found = [self.model_bad()]
            if expand is not None:
                found += expand(found[0])
            for bad in found:
                if len(found) > 1 and any(d <= bad for d in out.bad_sets):
                    continue
                if quota.reached(k):
                    out.cut_by = Bound.MAX_COUNT
                    return False
                out.bad_sets.append(bad)
                quota.add(bad)
                self.solver.add_clause([-self.ab_vars[i] for i in bad] + [-act])

    def model_bad(self) -> frozenset[int]:
        """Indexes (into ``theory.components``) of the components abnormal in the model."""
        model = self._last.get_model()
        assert model is not None
        # the health variables are 1..n, allocated first (see __init__)
        return frozenset(i for i, x in enumerate(model[: len(self.ab_vars)]) if x > 0)

    def core(self) -> list[int]:
        core = self._last.get_core()
        return [] if core is None else list(core)

    def close(self) -> None:
        self.stop_budget()
        self._watchdog.close()
        self.solver.delete()
        if self._plain is not None:
            self._plain.delete()
        if self._tot is not None:
            self._tot.delete()
