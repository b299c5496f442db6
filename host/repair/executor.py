"""The executor: runs a repair plan through the actuators and verifies every effect.

``Executor.execute(plan)`` runs the plan's steps as its partial order allows: every step whose
predecessors are done starts at once, so independent steps run in parallel (the actuators
still space switch-ons on the board); ``max_parallel=1`` runs them one at a time, in the
plan's order (``dxboard experiment`` compares the two). A ``start_node`` or
``reconfigure_node`` (``EARLY``: a node that connects to what it needs) does not wait for
the verification of the steps that bring up what it needs (``ENABLING``: a device's power-up
or power cycle, the start of a node publishing its inputs): it starts once they have acted
(a power cycle's off time over), like a driver that retries while its device boots, and its
own effect is due once theirs is, plus its settle time; it succeeds only when they are
verified too. So the critical path is the devices' boot and the nodes' first outputs, not the
sum of every step's settle time. Each step:

1. is checked (a protected component is never switched off; an action without actuator is
   refused) and reported ``started``;
2. runs through its actuator within ``step_timeout`` seconds (longer for a ``stop_node``
   whose process may take ``stop_timeout_s`` to stop) — else ``timeout``;
3. waits for its intended effect (``host.repair.effects``), ending the moment it is seen:
   output (``ok(t)`` of the topics a started node publishes, none of them ok before the step:
   else a refresh could pass for new messages), or the immediate effect of a ``stop_node`` or
   ``shutdown``, in any observation made since the step began (the process observer may see
   it before the actuator returns); a state alone (``running(n)``, ``on(d)``, ``in_band(d)``)
   in one made since the step began that still stands once the step has settled (a process
   that dies at once, a device that trips while it boots do not pass: observers report such
   a change at once); what the step only keeps (``kept``: a reconfigured node's process) in
   any observation that still stands. The deadline is settle + ``verify_s`` + the longest
   time an observer of the expected atoms needs to judge one (``judge_s``: two periods of a
   slow topic, whose rate is judged from two messages), all times ``stretch()`` (a power
   step's settle, the device's own boot time, excepted) (at least 1:
   the daemon passes ``load_stretch``, so a step started while the machine is busy gets the
   time a busy machine needs to start a process) (``Beliefs.wait_for``), the settle counted
   again from the moment the steps it waits for were verified if that was later (a node whose
   input came late gets its own time after it) — after it ``failed`` with what was seen
   instead, and at once when the board trips the channel the step switched on; then
   ``succeeded``.

On the first failed step nothing new starts; steps already running finish, and ``execute``
returns ``ExecutionResult(outcome=FAILED, failed=step, reason=...)`` so the caller
re-diagnoses and replans (``host.repair.loop.RepairLoop``). Every step's states are reported
through ``report`` as ``StepReport`` values (``to_record()`` gives the journal's
``ActionRecord``), and every quarantine as a ``Quarantined``.

Limits (``host.repair.limits``): each execution counts one attempt for every component it
repairs (the diagnosis it was given; without one, every component its steps touch), marked
verified when every effect was observed (a verified attempt stops counting once the repair has
held). A component that has used ``max_attempts`` in the window is quarantined — after a failed
step of its repair, or before a repair of it would run — and so is, at once, a device whose
step the board judged unsafe to repeat (``Unsafe``: a channel latched for a short circuit); a
quarantined component is put in its safe state (a device switched off, a node stopped; never a
protected component; the safe-state actions are reported like steps, under the plan id
``quarantine:<component>``) and no step touching it runs again (``BLOCKED``) until
``clear_quarantine(component)``; nor does one touching a component a person ``held``. Two executions
touching the same component never overlap (``BUSY``). With ``dry_run=True`` the executor
checks and reports every step and acts on nothing: no actuator, no wait, no attempt counted.
"""

from __future__ import annotations

import asyncio
import itertools
import logging
import math
import os
import time
from collections.abc import Callable, Collection, Iterable, Mapping, Sequence
from dataclasses import dataclass
from enum import StrEnum

from host.errors import DxboardError
from host.events import ActionRecord, ActionState, PlanRecord, PlanStep
from host.planning.plan import Plan, Step
from host.repair.actuators import Actuators, Refused, Unsafe
from host.repair.beliefs import Beliefs
from host.repair.effects import (
    DEFAULT_DEVICE_SETTLE_S,
    IMMEDIATE,
    contradictions,
    expected_effects,
    kept,
)
from host.repair.limits import AttemptLimiter, Quarantine, Quarantined

log = logging.getLogger(__name__)

DEFAULT_STEP_TIMEOUT_S = 10.0
DEFAULT_VERIFY_S = 5.0
QUARANTINE_PLAN = "quarantine"
#: steps after which a node may start before their effects are verified: what they bring up
#: comes on by itself (a device boots, a driver's first output flows); the node retries
ENABLING = frozenset({"power_up", "power_cycle", "start_node"})
#: steps that may start once the ENABLING steps before them have acted: a node started, or a
#: managed node's lifecycle transitions (a fresh connection to a device that still boots)
EARLY = frozenset({"start_node", "reconfigure_node"})
TRIP_MARGIN_S = 0.05  # a wait that ended this much before its deadline was ended by a trip
MAX_STRETCH = 3.0  # a busy machine's steps get at most this many times their time
DEVICE_STEPS = frozenset({"power_up", "power_cycle", "shutdown"})  # a device's own time


def runnable_now(path: str = "/proc/loadavg") -> float:
    """How many tasks other than this reader can run at this instant (Linux: the fourth field
    of ``/proc/loadavg``, ``running/total``); 0 where that is not known."""
    try:
        with open(path) as f:
            return max(0.0, float(f.read().split()[3].split("/")[0]) - 1)
    except (OSError, IndexError, ValueError):
        return 0.0


def load_stretch(getloadavg: Callable[[], tuple[float, float, float]] = os.getloadavg,
                 cores: int | None = None, runnable: Callable[[], float] = runnable_now
                 ) -> float:
    """How many times its settle and verify time a step gets: the load per core, at least 1
    (an idle or normally busy machine), at most ``MAX_STRETCH`` (a broken step still fails
    within a bounded time). The load is the one-minute load average or, when more, the tasks
    runnable now: the average lags a burst by a minute (on a machine that had just become busy
    a driver's first start got 12 s, unstretched, and its first 0.5 Hz output came later)."""
    try:
        load = getloadavg()[0]
    except OSError:  # no load average on this system
        load = 0.0
    load = max(load, runnable())
    return min(MAX_STRETCH, max(1.0, load / (cores or os.cpu_count() or 1)))


class Outcome(StrEnum):
    DONE = "done"  # every step ran and its effect was observed
    FAILED = "failed"  # a step failed, timed out or its effect did not appear
    QUARANTINED = "quarantined"  # a component used its attempts: quarantined, plan not run
    BLOCKED = "blocked"  # the plan touches a quarantined component: not run
    BUSY = "busy"  # another execution is repairing one of its components: not run


@dataclass(frozen=True)
class StepReport:
    """One state of one step (``started``, then ``succeeded``, ``failed`` or ``timeout``)."""

    plan_id: str
    action_id: str
    step: Step
    state: ActionState
    started: float
    finished: float | None = None
    detail: str = ""

    def to_record(self) -> ActionRecord:
        return ActionRecord(self.action_id, self.step.action, self.step.args, self.state,
                            self.started, self.finished, self.plan_id, self.detail)


Event = StepReport | Quarantined


class _Progress:
    """One execution's shared state: when each started step's effect is due, and whether
    it was verified (a future per step), for the steps that started before it was."""

    def __init__(self, plan: Plan) -> None:
        self.plan = plan
        self.due: dict[int, float] = {}  # step id -> its effect is due by (it has acted)
        self.verified: dict[int, asyncio.Future[bool]] = {}
        self.changed = asyncio.Event()
        loop = asyncio.get_running_loop()
        for s in plan.steps:
            self.verified[s.id] = loop.create_future()

    def acted(self, step: int, due: float) -> None:
        self.due[step] = due
        self.changed.set()

    def settled(self, step: int, ok: bool) -> None:
        f = self.verified[step]
        if not f.done():
            f.set_result(ok)


Reporter = Callable[[Event], None]


@dataclass(frozen=True)
class ExecutionResult:
    outcome: Outcome
    plan_id: str
    done: tuple[Step, ...] = ()
    failed: Step | None = None
    reason: str = ""
    quarantined: tuple[Quarantined, ...] = ()
    dry_run: bool = False

    @property
    def ok(self) -> bool:
        return self.outcome is Outcome.DONE


def within(seconds: float) -> str:
    """``within 12.9 s``: a computed time limit as a person reads it (not ``12.8619``)."""
    return f"within {seconds:.1f} s" if seconds < 100 else f"within {seconds:.0f} s"


def plan_record(plan: Plan, plan_id: str, repairs: Iterable[str] = ()) -> PlanRecord:
    """The journal's record of a plan."""
    return PlanRecord(plan_id, tuple(PlanStep(s.action, s.args) for s in plan.steps),
                      tuple(sorted(repairs)))


def touched(plan: Plan, repairs: Iterable[str] = ()) -> frozenset[str]:
    """The components a plan acts on or repairs."""
    return frozenset(s.args[0] for s in plan.steps if s.args) | frozenset(repairs)


class Executor:
    def __init__(self, actuators: Actuators, beliefs: Beliefs, *,
                 settle: Mapping[str, float] | None = None,
                 limiter: AttemptLimiter | None = None, report: Reporter | None = None,
                 dry_run: bool = False, step_timeout: float = DEFAULT_STEP_TIMEOUT_S,
                 verify_s: float = DEFAULT_VERIFY_S, observable: Collection[str] | None = None,
                 clock: Callable[[], float] = time.monotonic,
                 max_parallel: int | None = None,
                 stretch: Callable[[], float] = lambda: 1.0,
                 judge_s: Mapping[str, float] | None = None) -> None:
        self.actuators = actuators
        self.model = actuators.model
        self.beliefs = beliefs
        self.settle = dict(settle or {})
        self.limiter = limiter or AttemptLimiter()
        self.quarantine = Quarantine()
        self.report = report
        self.dry_run = dry_run
        self.step_timeout = step_timeout
        self.verify_s = verify_s
        self.observable = observable
        self.clock = clock
        self.max_parallel = max_parallel  # steps running at once; None: as the order allows
        self.stretch = stretch  # how many times its settle and verify a step gets (>= 1)
        # atom -> how long its observer needs to judge it once its cause is there (a slow
        # topic's rate needs two of its messages): added to the verify time of a step
        # expecting it
        self.judge_s = dict(judge_s or {})
        self.held: dict[str, str] = {}  # component -> why a person holds it (left alone)
        self._busy: set[str] = set()
        self._unsafe: set[str] = set()  # devices whose last step was unsafe to repeat
        self._ids = itertools.count(1)

    # -- public ----------------------------------------------------------------------------
    async def execute(self, plan: Plan, plan_id: str = "",
                      repairs: Iterable[str] = ()) -> ExecutionResult:
        """Run ``plan`` (see the module docstring); never raises for a failed step."""
        plan_id = plan_id or f"plan-{next(self._ids)}"
        comps = touched(plan, repairs)
        blocked = sorted(c for c in comps if c in self.quarantine)
        if blocked:
            return ExecutionResult(Outcome.BLOCKED, plan_id, reason=f"{', '.join(blocked)} "
                                   "quarantined: cleared only by a person", dry_run=self.dry_run)
        held = sorted(c for c in comps if c in self.held)
        if held:
            return ExecutionResult(Outcome.BLOCKED, plan_id, reason=f"{', '.join(held)} held "
                                   "by a person: left alone", dry_run=self.dry_run)
        busy = sorted(comps & self._busy)
        if busy:
            return ExecutionResult(Outcome.BUSY, plan_id, reason=f"{', '.join(busy)} already "
                                   "being repaired", dry_run=self.dry_run)
        if self.dry_run:
            return await self._dry_run(plan, plan_id)
        now = self.clock()
        targets = frozenset(repairs) or comps
        spent = sorted(c for c in targets if self.limiter.exhausted(c, now))
        if spent:
            q = [await self.quarantine_component(
                c, f"{self.limiter.count(c, now)} repair attempts in "
                f"{self.limiter.window_s:g} s") for c in spent]
            return ExecutionResult(Outcome.QUARANTINED, plan_id, quarantined=tuple(q),
                                   reason=f"{', '.join(spent)} used their repair attempts")
        for c in targets:
            self.limiter.record(c, now)
        self._busy |= comps
        try:
            result = await self._run(plan, plan_id, targets)
        finally:
            self._busy -= comps
        if result.ok:
            for c in targets:
                self.limiter.verified(c, self.clock())
        return result

    async def quarantine_component(self, component: str, reason: str,
                                   by: str = "daemon") -> Quarantined:
        """Take ``component`` out of automatic repair and leave it in a safe state."""
        old = self.quarantine.get(component)
        if old is not None:
            return old
        safe = "left as is (dry run)" if self.dry_run else await self._safe_state(component)
        entry = Quarantined(component, self.clock(), reason, safe, by)
        self.quarantine.add(entry)
        log.warning("quarantined %s: %s; %s", component, reason, safe)
        self._emit(entry)
        return entry

    def clear_quarantine(self, component: str) -> bool:
        """A person cleared ``component``: it may be repaired again, with fresh attempts."""
        self.limiter.reset(component)
        return self.quarantine.clear(component)

    # -- running a plan --------------------------------------------------------------------
    async def _run(self, plan: Plan, plan_id: str, targets: frozenset[str]) -> ExecutionResult:
        done: list[Step] = []
        started: set[int] = set()
        failure: tuple[Step, str] | None = None
        tasks: dict[asyncio.Task[str | None], Step] = {}
        prog = _Progress(plan)
        try:
            while True:
                if failure is None:
                    for s in self._ready(plan, prog, {d.id for d in done}, started):
                        if self.max_parallel is not None and len(tasks) >= self.max_parallel:
                            break
                        started.add(s.id)
                        waits = [p for p in plan.after[s.id] if p not in {d.id for d in done}]
                        task = asyncio.get_running_loop().create_task(
                            self._step(s, plan_id, prog, waits), name=f"step:{s}")
                        tasks[task] = s
                if not tasks:
                    break
                prog.changed.clear()  # no await since the ready steps were taken
                waiter = asyncio.get_running_loop().create_task(prog.changed.wait())
                try:
                    await asyncio.wait([*tasks, waiter], return_when=asyncio.FIRST_COMPLETED)
                finally:
                    waiter.cancel()
                for t in [t for t in tasks if t.done()]:
                    s = tasks.pop(t)
                    why = t.result()
                    if why is None:
                        done.append(s)
                    elif failure is None:
                        failure = (s, why)
        finally:
            for t in tasks:
                t.cancel()
        if failure is None:
            return ExecutionResult(Outcome.DONE, plan_id, tuple(done))
        step, why = failure
        q: list[Quarantined] = []
        now = self.clock()
        if step.args and step.args[0] in self._unsafe:  # the board's judgement: stop now
            self._unsafe.discard(step.args[0])
            q.append(await self.quarantine_component(step.args[0], f"{step} failed: {why}"))
        else:
            # a repair that does not work quarantines what it repairs, not the driver it
            # restarts on the way (a hung lidar, not its node)
            for c in sorted(targets):
                if self.limiter.exhausted(c, now) and c not in self.quarantine:
                    q.append(await self.quarantine_component(
                        c, f"{step} failed ({why}) after {self.limiter.count(c, now)} repair "
                        f"attempts in {self.limiter.window_s:g} s"))
        return ExecutionResult(Outcome.FAILED, plan_id, tuple(done), step, why, tuple(q))

    @staticmethod
    def _ready(plan: Plan, prog: _Progress, done: set[int], started: set[int]) -> list[Step]:
        """Steps that may start: every predecessor done, except that a node may start once
        the steps that bring up what it needs have *acted* (their effects still pending)."""
        out = []
        for s in plan.steps:
            if s.id in started or s.id in done:
                continue
            early = s.action in EARLY
            if all(p in done or (early and plan.steps[p].action in ENABLING and p in prog.due)
                   for p in plan.after[s.id]):
                out.append(s)
        return out

    def _timeout(self, step: Step) -> float:
        if step.action == "stop_node" and self.actuators.supervisor is not None:
            cfg = self.actuators.supervisor.configs.get(step.args[0])
            if cfg is not None:
                return max(self.step_timeout, cfg.stop_timeout_s + 2.0)
        return self.step_timeout

    def settle_of(self, step: Step) -> float:
        if step.action in IMMEDIATE or not step.args:
            return 0.0
        settle = self.settle.get(step.args[0], DEFAULT_DEVICE_SETTLE_S)
        if step.action == "power_cycle":
            settle += self.actuators.off_s
        return settle

    def stretched_settle(self, step: Step, k: float) -> float:
        """The settle time of ``step`` on a machine busy ``k`` times over: a process starts
        ``k`` times slower; a device boots in its own time whatever the computer's load, so
        a power step's settle is not stretched (only the window after it, in which the loaded
        computer must see the effect)."""
        return self.settle_of(step) * (1.0 if step.action in DEVICE_STEPS else k)

    async def _step(self, step: Step, plan_id: str, prog: _Progress | None = None,
                    waits: Sequence[int] = ()) -> str | None:
        """Run one step; None when it worked, else why not (already reported)."""
        ok = False
        try:
            why = await self._act_and_verify(step, plan_id, prog, waits)
            ok = why is None
            return why
        finally:  # its dependents learn the outcome, however it ended (even cancelled)
            if prog is not None:
                prog.settled(step.id, ok)

    async def _act_and_verify(self, step: Step, plan_id: str, prog: _Progress | None,
                              waits: Sequence[int]) -> str | None:
        action_id = f"{plan_id}/{step.id}"
        t0 = self.clock()
        self._emit(StepReport(plan_id, action_id, step, ActionState.STARTED, t0))

        def finish(state: ActionState, detail: str) -> None:
            self._emit(StepReport(plan_id, action_id, step, state, t0, self.clock(), detail))

        expected = expected_effects(step, self.model, self.observable)
        outputs = [a for a in expected if a.startswith("ok(")]
        # a topic already ok before the step (the node's previous instance) could be refreshed
        # after it without one new message: then only an observation once settled counts
        early = bool(outputs) and all(self.beliefs.value(a) is not True for a in outputs)
        timeout = self._timeout(step)
        try:
            detail = await asyncio.wait_for(self.actuators.run(step), timeout)
        except TimeoutError:
            why = f"no answer {within(timeout)}"
            finish(ActionState.TIMEOUT, why)
            return why
        except Refused as exc:
            finish(ActionState.FAILED, f"refused: {exc}")
            return f"refused: {exc}"
        except Unsafe as exc:
            self._unsafe.add(exc.device)
            finish(ActionState.FAILED, str(exc))
            return str(exc)
        except DxboardError as exc:
            finish(ActionState.FAILED, str(exc))
            return str(exc)
        end = self.clock()
        k = max(1.0, self.stretch())  # a busy machine starts a process slowly: more time
        settle = self.stretched_settle(step, k)
        acted = end
        if step.action == "power_cycle":  # the channel is back on only after the off time
            acted += self.actuators.off_s
            await asyncio.sleep(max(0.0, acted - self.clock()))
        # the effect is due once this step and what it waits for have settled
        due = max([end, *(prog.due[p] for p in waits if prog is not None)]) + settle
        settled = due  # ... and, if what it waits for came later than due, settle after that
        if prog is not None:
            prog.acted(step.id, due)
            for p in waits:
                if not await prog.verified[p]:
                    why = f"not verified: {prog.plan.steps[p]} failed"
                    finish(ActionState.FAILED, f"{detail}; {why}")
                    return why
            if waits:
                settled = max(due, self.clock() + settle)
        if expected:
            # output (a topic flowing) ends the wait the moment it is seen, and so does an
            # immediate effect (a process gone, a channel off); a state alone (a process
            # running, a channel on) must still hold once the step has settled: that is waited
            # out first (a trip ends it). Each counts in any observation made since the step
            # began (the process observer may see it before the actuator returns) that still
            # stands: observers report a change at once, so no refresh is waited for.
            fresh = t0
            deadline = settled + (self.verify_s + max(
                (self.judge_s.get(a, 0.0) for a in expected), default=0.0)) * k
            abort = contradictions(step, self.observable)
            if not early and step.action not in IMMEDIATE:
                if abort:
                    await self.beliefs.wait_for(abort, end, due - self.clock())
                else:
                    await asyncio.sleep(max(0.0, due - self.clock()))
            # what the step keeps (a reconfigured node's process) must hold, not be new
            keeps = {a: v for a, v in expected.items() if a in kept(step)}
            new = {a: v for a, v in expected.items() if a not in keeps}
            if not (await self.beliefs.wait_for(new, fresh, deadline - self.clock(),
                                                abort=abort, abort_after=end)
                    and not self.beliefs.missing(keeps, -math.inf)):
                seen = {**self.beliefs.missing(new, fresh),
                        **self.beliefs.missing(keeps, -math.inf)}
                why = "effect not observed {}{}: {}".format(
                    within(deadline - end), "" if k == 1.0 else f" (stretched {k:.1f}x: "
                    "the machine is busy)", "; ".join(f"{a} {v}" for a, v in seen.items()))
                waited = self.clock() - end
                if waited < deadline - end - TRIP_MARGIN_S:
                    why = "the board tripped it {:.1f} s after the step: {}".format(
                        waited, "; ".join(f"{a} {v}" for a, v in seen.items()))
                finish(ActionState.FAILED, f"{detail}; {why}")
                return why
            detail += "; observed " + ", ".join(
                a if v else f"~{a}" for a, v in sorted(expected.items()))
        finish(ActionState.SUCCEEDED, detail)
        return None

    async def _dry_run(self, plan: Plan, plan_id: str) -> ExecutionResult:
        done: list[Step] = []
        for layer in plan.layers():
            for step in layer:
                action_id = f"{plan_id}/{step.id}"
                t = self.clock()
                self._emit(StepReport(plan_id, action_id, step, ActionState.STARTED, t))
                try:
                    self.actuators.check(step)
                except Refused as exc:
                    self._emit(StepReport(plan_id, action_id, step, ActionState.FAILED, t, t,
                                          f"dry run: refused: {exc}"))
                    return ExecutionResult(Outcome.FAILED, plan_id, tuple(done), step,
                                           f"refused: {exc}", dry_run=True)
                expected = expected_effects(step, self.model, self.observable)
                self._emit(StepReport(plan_id, action_id, step, ActionState.SUCCEEDED, t, t,
                                      "dry run: not carried out; would expect "
                                      + (", ".join(a if v else f"~{a}"
                                                   for a, v in sorted(expected.items()))
                                         or "nothing observable")))
                done.append(step)
        return ExecutionResult(Outcome.DONE, plan_id, tuple(done), dry_run=True)

    # -- quarantine ------------------------------------------------------------------------
    async def _safe_state(self, component: str) -> str:
        """Switch ``component`` off or stop it where allowed; what was done."""
        if component in self.actuators.protected:
            return "left as is: protected"
        c = self.model.components.get(component)
        if c is None:
            return "left as is: not a component of the model"
        sup = self.actuators.supervisor
        if c.channel is not None and self.actuators.board is not None:
            action = "shutdown"
        elif c.is_node and sup is not None and component in sup.configs:
            action = "stop_node"
        else:
            return "left as is: nothing can switch it off"
        step = Step(0, action, (component,))
        why = await self._step(step, f"{QUARANTINE_PLAN}:{component}")
        return f"{step}" if why is None else f"{step} failed: {why}"

    def _emit(self, event: Event) -> None:
        if self.report is None:
            return
        try:
            self.report(event)
        except Exception:  # a broken journal must not stop a repair half-way
            log.exception("reporting %s failed", event)
