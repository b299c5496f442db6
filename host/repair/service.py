"""The repair service: from a changed diagnosis to verified repairs, one at a time, never on
stale data — knowing nothing of the daemon that feeds it.

``RepairService`` is fed, and emits; it reads nothing of its owner:

- ``diagnosed(result)``: a diagnosis changed. When it names broken components a repair starts
  after ``debounce_s`` (a component that keeps entering and leaving the diagnosis faster than
  that is reported, ``host.repair.unsettled``) — unless a newer diagnosis superseded it, the
  board link is down (then every board literal is unknown: nothing to act on), or a repair is
  already running (the running loop re-diagnoses after each plan, so it sees the change).
  The debounce keeps a repair off what does not hold: a reading that flickers, a verdict a
  busy machine overturns a moment later. Evidence its observer already confirmed before
  saying it needs no second wait (``confirmed(atom)``, the observer hub's: a silence judged in
  the publisher's own time, a trip the board's readings bore out): a diagnosis that changed
  with such a finding new since the last one starts its repair after ``confirmed_debounce_s``
  (default 0); any other change, a flapping diagnosis among them, still waits ``debounce_s``.
  A topic's silence is no such finding while an input it depends on (the model's
  ``publishes``) is observed and still ok: the input stopping first is judged a moment later
  when its own silence is longer (a 45 Hz map pose judged silent 12 ms before the 40 Hz scan it
  follows made a learned model restart the mapper for a lidar hang), so it gets the debounce;
- ``link(client)``: the board link it acts through (``None``: the link is down); back up,
  it starts the repair of what the latest diagnosis names after ``debounce_s``, so a repair
  refused while the link was down is not forgotten;
- ``diagnose``: given at construction, an async callable returning a fresh diagnosis of the
  observations now (the daemon runs it off its loop); ``observations``: the daemon's one
  observation set, whose literals go into each repair problem;
- ``emit``: one callback for everything it does — ``PlanRecord``, ``ActionRecord`` (each state
  of each step), ``QuarantineChange``, ``HoldChange``, ``RepairEnded`` and ``Note`` events
  (``host.events``).

A person (``host.operator``) can quarantine a component or clear its quarantine, and hold a
component (maintenance: no repair touches it) or release it; a channel switched off on the board
by a command this host did not send is held the same way until it is switched on again, so a
deliberate switch-off is not undone. Quarantines and holds a previous run left in the journal
are ``restore``d at start.

While the board's own protection has the channels (it sheds them for input under-voltage and
restores them itself afterwards, or retries a channel it tripped: a power-up then would only
wait for that retry, spend one of the device's attempts and, when the trip was its noisy
sensor's doing, power-cycle a healthy device; the wait for a retry lasts at most
``RETRY_WAIT_MS`` of the board's own clock and ``RETRY_WAIT_CAP_S`` of ours) repairs wait for
it rather than fight it. A channel the board
shed to stay under its total-current limit is no fault of its device and stays off until it is
commanded on: the device is held (``SHED_HOLD``, shown like any hold) while the board keeps it
shed, so no repair switches it back for the board to shed again, and the diagnosis turns to the
channel whose current is abnormal; the hold ends when the channel is switched on or off.

A repair is the ``RepairLoop``: diagnose, choose, plan, execute with verified effects, until
healthy, bounded by the executor's attempt limiter and quarantine. With ``dry_run`` plans are
made and reported but nothing acts. ``build`` makes a service for a robot: from its planner
(``repair.pddl``) and its ``processes:`` (of ``system.yaml``), the process supervisor, the
actuators (board power through the linked ``BoardClient``, nodes through the supervisor) and the
executor, whose effect checks wait on the same observation set the diagnoser reads.
"""

from __future__ import annotations

import asyncio
import contextlib
import logging
import time
from collections.abc import Awaitable, Callable, Collection, Mapping, Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

from host.diagnosis.logic import Literal
from host.diagnosis.observations import ObservationSet
from host.diagnosis.result import DiagnosisResult
from host.errors import RemoteError
from host.events import Event, HoldChange, Note, PlanRecord, QuarantineChange, RepairEnded
from host.repair.actuators import Actuators
from host.repair.beliefs import ObservedBeliefs
from host.repair.booting import (
    MAX_WAIT_FACTOR,
    booting,
    came_back,
    describe,
    up_atom,
    up_since,
)
from host.repair.crashloop import CrashLoops, blame_devices
from host.repair.effects import settle_times
from host.repair.executor import Event as ExecutorEvent
from host.repair.executor import Executor, StepReport, load_stretch
from host.repair.limits import AttemptLimiter, Quarantined
from host.repair.loop import RepairLoop
from host.repair.planner import RepairPlanner
from host.repair.policy import Candidate
from host.repair.processes import ProcessConfig
from host.repair.supervisor import ProcessSupervisor
from host.repair.unsettled import Unsettled
from protocol.constants import (
    B_OVER_TOTAL,
    B_UV_OFF,
    B_UV_SHED,
    F_SENSOR,
    F_SHED_TOTAL,
    F_SHED_UV,
    ST_TRIPPED,
)

if TYPE_CHECKING:
    from host.board.client import BoardClient
    from host.board.types import BoardState
    from host.diagnosis.model import SystemModel

log = logging.getLogger(__name__)

BOARD_POLL_S = 0.5
# a tripped channel is left to the board's retry this long on its own clock (its uptime): longer
# than its longest default retry delay (5 s); the board's clock, not ours, because a busy
# machine delays the board's retry and our view of it alike. Bounded on our clock all the same.
RETRY_WAIT_MS = 6000
RETRY_WAIT_CAP_S = 12.0
FOREIGN_WINDOW_S = 5.0  # a switch command this host sent that long ago is still its own
SHED_HOLD = "shed by the board to stay under its total-current limit"
Emit = Callable[[Event], None]
Confirmed = Callable[[str], bool]  # is what is said of this atom a confirmed abnormal finding?
FreshDiagnosis = Callable[[], Awaitable[DiagnosisResult]]


def is_healthy(result: DiagnosisResult | None) -> bool:
    """True when ``result`` says nothing is broken."""
    return result is not None and result.bad_sets() in ([], [frozenset()])


class RepairService:
    def __init__(self, planner: RepairPlanner, executor: Executor, *, diagnose: FreshDiagnosis,
                 observations: ObservationSet, emit: Emit, board: str = "board",
                 debounce_s: float = 0.5, confirmed: Confirmed | None = None,
                 confirmed_debounce_s: float = 0.0) -> None:
        self.planner = planner
        self.executor = executor
        self.observations = observations
        self.board_component = board
        self.debounce_s = debounce_s
        self.confirmed = confirmed
        self.confirmed_debounce_s = confirmed_debounce_s
        # channel -> (boot id, board uptime ms, our clock) when it was first seen TRIPPED
        self._tripped_at: dict[int, tuple[int, int, float]] = {}
        self._seen: frozenset[Literal] = frozenset()  # the literals at the last diagnosis
        # device -> when it came back on, for the restored devices spared once already: if
        # restarting their drivers did not do it, the device is blamed again (a lidar that
        # hangs just after a brown-out is the lidar's fault)
        self._spared: dict[str, float | None] = {}
        self._healthy_at: float | None = None  # the latest all-healthy diagnosis
        self._fresh = diagnose
        self._emit = emit
        executor.report = self._report
        self.loop = RepairLoop(planner, executor, self._diagnose, on_plan=self._plan)
        self._client: BoardClient | None = None
        self._latest: DiagnosisResult | None = None
        self._pending: asyncio.Task[Any] | None = None
        self._running: asyncio.Task[Any] | None = None
        self.unsettled = Unsettled()
        self.crashloops = CrashLoops(observations, executor.settle,
                                     [c.name for c in executor.model.components.values()
                                      if c.is_node], executor.actuators.stops,
                                     executor.stretch)
        self._loop_notes: list[str] = []

    # --- inputs -------------------------------------------------------------------------
    def link(self, client: BoardClient | None) -> None:
        """The board link repairs act through; None while it is down. Back up, it starts the
        repair of what the latest diagnosis names, after the debounce, unless one is running
        or due: one refused while the link was down would otherwise wait for the diagnosis to
        change (a reboot's devices, found off a moment before the new boot's state)."""
        back = self._client is None and client is not None
        self._client = client
        self.executor.actuators.board = client
        latest = self._latest
        if back and latest is not None and not is_healthy(latest) and not self.active:
            self._pending = asyncio.ensure_future(self._after_debounce(latest, self.debounce_s))

    def diagnosed(self, result: DiagnosisResult) -> None:
        """A diagnosis changed: start a repair after the debounce if it names anything."""
        self._latest = result
        named = set().union(*result.bad_sets()) if result.bad_sets() else set()
        for flip in self.unsettled.diagnosed(named, self.executor.clock(), not self.busy):
            self._emit(Note(flip.text(), "warning"))
        firm = self._confirmed_news()
        if self._pending is not None:
            self._pending.cancel()
            self._pending = None
        if is_healthy(result):
            self._healthy_at = self.executor.clock()
        if is_healthy(result) or self.busy:
            return  # nothing to do, or the running loop re-diagnoses by itself
        wait = self.debounce_s
        if firm:
            wait = self.confirmed_debounce_s
            self._emit(Note(f"repair after {wait:g} s, not the {self.debounce_s:g} s debounce: "
                            f"{', '.join(firm)} confirmed by its observer"))
        self._pending = asyncio.ensure_future(self._after_debounce(result, wait))

    def _confirmed_news(self) -> list[str]:
        """The literals new since the last diagnosis that their observers confirmed."""
        now = frozenset(self.observations.literals())
        new, self._seen = now - self._seen, now
        if self.confirmed is None:
            return []
        ok = {x.atom: x.positive for x in now}
        return sorted(str(x) for x in new if self.confirmed(x.atom)
                      and not any(ok.get(f"ok({u})") for u in self._inputs(x.atom)))

    def _inputs(self, atom: str) -> set[str]:
        """The topics the output topic of ``ok(/t)`` depends on (every publisher's inputs, by
        the model), and theirs in turn; empty for any other atom."""
        if not (atom.startswith("ok(/") and atom.endswith(")")):
            return set()
        todo, seen = [atom[3:-1]], set[str]()
        while todo:
            topic = todo.pop()
            for c in self.executor.model.publishers(topic):
                for u in c.publishes[topic]:
                    if u not in seen:
                        seen.add(u)
                        todo.append(u)
        return seen

    @property
    def busy(self) -> bool:
        """A repair is running."""
        return self._running is not None and not self._running.done()

    @property
    def active(self) -> bool:
        """A repair is running or about to start (its debounce is pending)."""
        return self.busy or (self._pending is not None and not self._pending.done())

    # --- repairing ----------------------------------------------------------------------
    async def _after_debounce(self, result: DiagnosisResult, wait: float) -> None:
        await asyncio.sleep(wait)
        now = self._latest
        if now is None or now.bad_sets() != result.bad_sets() or self.busy:
            return  # superseded
        if self._client is None:
            self._emit(Note("no repair while the board link is down"))
            return
        self._running = asyncio.ensure_future(self._repair())

    async def _board_busy(self) -> str:
        """Why the board's own protection has the channels now (empty: it has not).

        Under input under-voltage the board sheds channels, refuses to switch them on and
        restores them itself, spaced, once the voltage is back: a repair would fight it and
        spend the devices' attempts on refusals. So repairs wait until the board is done."""
        client = self._client
        if client is None:
            return "the board link is down"
        try:
            state = await client.state()
        except RemoteError as exc:  # the link went down under us: wait for it like the rest
            return f"the board does not answer ({exc.message})"
        self._hold_shed(state)
        shed = [c.name for c in state.channels if c.live_faults & F_SHED_UV]
        if shed or state.board_flags & (B_UV_SHED | B_UV_OFF):
            # the devices lose power through no fault of their own, and their drivers their
            # devices: bringing them back spends no repair attempt (a fourth brown-out within
            # the limiter's window quarantined every driver, issue 25 item 7)
            self.executor.limiter.board_rebooted()
        if state.board_flags & (B_UV_SHED | B_UV_OFF):
            return "the board sheds channels for input under-voltage"
        if state.board_flags & B_OVER_TOTAL:
            return "the board is over its total-current limit"
        if shed:
            return f"the board is restoring {', '.join(shed)} after an under-voltage"
        # a channel the board tripped has its retry pending (with no retry left it latches):
        # a power-up would only wait for it, spend an attempt, and, when the trip was a noisy
        # sensor's (its first two samples can read like a short's), power-cycle a healthy
        # device. Each trip is left to the board for its retry, on the board's clock.
        now = self.executor.clock()
        tripped = {c.channel: c for c in state.channels if c.state == ST_TRIPPED}
        seen = {ch: self._tripped_at.get(ch, (state.boot_id, state.uptime_ms, now))
                for ch in tripped}
        self._tripped_at = {ch: (b, up, t) if b == state.boot_id and up <= state.uptime_ms
                            else (state.boot_id, state.uptime_ms, now)  # the board rebooted
                            for ch, (b, up, t) in seen.items()}
        waiting = [c for ch, c in tripped.items()
                   if state.uptime_ms - self._tripped_at[ch][1] < RETRY_WAIT_MS
                   and now - self._tripped_at[ch][2] < RETRY_WAIT_CAP_S]
        doubted = [c.name for c in waiting if c.live_faults & F_SENSOR]
        if doubted:
            return (f"the board retries {', '.join(doubted)} itself (it doubts its current "
                    "sensor)")
        if waiting:
            return (f"the board has tripped {', '.join(c.name for c in waiting)} and retries "
                    "it itself")
        return ""

    def _hold_shed(self, state: BoardState) -> None:
        """Hold the devices the board keeps shed for its total current; release those it no
        longer does (switched on or off since)."""
        held = self.executor.held
        for c in self.executor.model.components.values():
            ch = next((x for x in state.channels if x.channel == c.channel), None)
            if ch is None or c.channel is None:
                continue
            if ch.live_faults & F_SHED_TOTAL:
                if c.name not in held:
                    self.hold(c.name, f"{SHED_HOLD}; switch it on when the cause is found",
                              by="board")
            elif held.get(c.name, "").startswith(SHED_HOLD):
                self.release(c.name, by="board")

    async def _wait_for_board(self) -> None:
        """Wait (noting why, once) while the board's own protection has the channels, then
        while a component that came up by other means than a repair step is still booting
        (``host.repair.booting``; at most ``MAX_WAIT_FACTOR`` times the longest settle)."""
        said = ""
        while reason := await self._board_busy():
            if reason != said:
                self._emit(Note(f"repairs wait: {reason}"))
                said = reason
            await asyncio.sleep(BOARD_POLL_S)
        ex = self.executor
        comps = [(c.name, c.is_node) for c in ex.model.components.values()
                 if c.is_node or c.channel is not None]
        k = max(1.0, ex.stretch())  # read once: the wait's bound must not move
        end = ex.clock() + MAX_WAIT_FACTOR * k * max(ex.settle.values(), default=0.0)
        while (left := booting(self.observations, ex.settle, comps, ex.clock(), k)) \
                and ex.clock() < end:
            if (reason := describe(left)).split(":")[0] != said.split(":")[0]:
                self._emit(Note(f"repairs wait: {reason}"))
                said = reason
            await asyncio.sleep(min(BOARD_POLL_S, max(left.values())))

    async def _repair(self) -> None:
        try:
            await self._wait_for_board()
            res = await self.loop.run()
        except RemoteError as exc:  # the board or a peer failed mid-repair: end it, say why
            self._emit(RepairEnded("interrupted", 0, str(exc)))
            return
        self._emit(RepairEnded(str(res.outcome), len(res.rounds), res.reason))

    async def _diagnose(self) -> tuple[Sequence[Candidate], Sequence[Literal]]:
        """The loop's view: a fresh diagnosis of what is observed now."""
        if self._client is None:  # board literals are unknown: only the link is to blame
            link = Candidate(frozenset({self.board_component}), 1.0)
            return [link], self.observations.literals()
        await self._wait_for_board()
        result = await self._fresh()
        cands = [Candidate(frozenset(d.bad), d.probability) for d in result.diagnoses]
        return self._blame_devices(self._spare_restored(cands)), self.observations.literals()

    def _blame_devices(self, cands: list[Candidate]) -> list[Candidate]:
        """A node that dies at once after every start, or whose device is quarantined and off,
        blames its device (``host.repair.crashloop``); each new finding is said once."""
        ex = self.executor
        out, notes = blame_devices(cands, self.crashloops, ex.model, self.observations,
                                   ex.quarantine.components | set(ex.held), ex.clock(),
                                   ex.quarantine.components)
        for n in notes:
            if n not in self._loop_notes:
                self._emit(Note(n))
        self._loop_notes = notes
        return out

    def _spare_restored(self, cands: list[Candidate]) -> list[Candidate]:
        """Leave out the candidates that blame a device the board has just restored by itself
        (``host.repair.booting.came_back``) when others explain the fault without it: its
        driver, which lost the device, is restarted instead of the device power-cycled again.
        Once per return of the device, and not once the robot was all healthy after it came
        back: then what is broken is a new fault, and the device may be to blame."""
        ex = self.executor
        back = came_back(self.observations, ex.settle,
                         [(c.name, c.channel) for c in ex.model.components.values()
                          if c.channel is not None and not c.is_node],
                         ex.actuators.commands, ex.clock())
        healthy = self._healthy_at
        back = {d for d in back  # spared once since it came back on: not again; nor once the
                # robot was whole after it came back (what broke since is a new fault)
                if (d not in self._spared
                    or self._spared[d] != up_since(self.observations, up_atom(d, False)))
                and (healthy is None
                     or healthy <= (up_since(self.observations, up_atom(d, False)) or 0.0))}
        keep = [c for c in cands if not c.bad & back]
        if not keep or len(keep) == len(cands):
            return cands
        spared = sorted(back & set().union(*(c.bad for c in cands)))
        for d in spared:
            self._spared[d] = up_since(self.observations, up_atom(d, False))
        self._emit(Note(f"{', '.join(spared)}: came on without a repair and booted; not blamed "
                        "while another diagnosis explains what is seen (once: if that repair "
                        "does not do it, it is)"))
        return keep

    # --- reporting ----------------------------------------------------------------------
    def _plan(self, record: PlanRecord) -> None:
        self._emit(record)
        if self.executor.dry_run:
            self._emit(Note(f"dry run: plan {record.plan_id} not carried out"))

    def _report(self, event: ExecutorEvent) -> None:
        if isinstance(event, StepReport):
            self._emit(event.to_record())
        elif isinstance(event, Quarantined):
            attempts = self.executor.limiter.count(event.component, self.executor.clock())
            self._emit(QuarantineChange(event.component, True, event.reason, event.safe_state,
                                        event.by, attempts))

    # --- what a person says (host.operator) ------------------------------------------------
    def components(self) -> list[str]:
        return list(self.executor.model.components)

    def listing(self) -> dict[str, dict[str, str]]:
        return {"quarantined": {q.component: q.reason
                                for q in self.executor.quarantine.entries()},
                "held": dict(self.executor.held)}

    async def quarantine(self, component: str, reason: str, by: str = "person") -> str:
        """Take ``component`` out of automatic repair now (its safe state applied)."""
        entry = await self.executor.quarantine_component(component, reason, by)
        return entry.safe_state

    async def clear(self, component: str, by: str = "person") -> list[str]:
        """Give ``component`` back to automatic repair, with fresh attempts, and with it the
        quarantined drivers that run on it (a device's permanent fault quarantines its driver
        too: one clear must bring the robot back); what was cleared, ``component`` first. A
        device the board latched for a short may be cleared and switched on once."""
        if not self.executor.clear_quarantine(component):
            return []
        cleared = [component]
        drivers = [c.name for c in self.executor.model.components.values()
                   if component in c.hardware]
        cleared += [d for d in drivers if self.executor.clear_quarantine(d)]
        self.executor.actuators.allow_unlatch(component)
        for c in cleared:
            self._emit(QuarantineChange(c, False, by=by))
        self._again()
        return cleared

    def hold(self, component: str, reason: str, by: str = "person") -> bool:
        """Leave ``component`` alone (maintenance) until it is released."""
        if component in self.executor.held:
            return False
        self.executor.held[component] = reason
        self._emit(HoldChange(component, True, reason, by))
        return True

    def release(self, component: str, by: str = "person") -> bool:
        if self.executor.held.pop(component, None) is None:
            return False
        self._emit(HoldChange(component, False, by=by))
        self._again()
        return True

    def restore(self, quarantined: Mapping[str, QuarantineChange],
                held: Mapping[str, HoldChange]) -> None:
        """Take the quarantines and holds a previous run left (from its journal): they stay
        until a person clears them, whatever restarted in between."""
        for c, q in quarantined.items():
            if c in self.executor.model.components and c not in self.executor.quarantine:
                self.executor.quarantine.add(Quarantined(
                    c, self.executor.clock(), q.reason, q.safe_state, q.by))
                self._emit(QuarantineChange(c, True, q.reason, q.safe_state, q.by, q.attempts))
        for c, h in held.items():
            if c in self.executor.model.components:
                self.hold(c, h.reason, h.by)

    async def adopt(self) -> None:
        """Take over the nodes an earlier daemon left running (and stop stale ones)."""
        sup = self.executor.actuators.supervisor
        if sup is None:
            return
        done = await sup.adopt()
        if done:
            self._emit(Note("nodes left by an earlier run: " + "; ".join(
                f"{n} {what}" for n, what in sorted(done.items()))))

    def board_rebooted(self) -> None:
        """The board rebooted: the devices lost power through no fault of their own, so their
        bring-up after it spends no repair attempt (``AttemptLimiter.board_rebooted``)."""
        self.executor.limiter.board_rebooted()

    def board_switched(self, channel: int, on: bool) -> None:
        """The board switched ``channel`` on or off by a command (not its protection): when this
        host did not send it, a person did — hold the device while it is off, so that the
        daemon does not undo a deliberate switch-off; release it when it is switched on."""
        if self.executor.actuators.sent_recently(channel, on, FOREIGN_WINDOW_S):
            return
        device = next((c.name for c in self.executor.model.components.values()
                       if c.channel == channel), None)
        if device is None:
            return
        if not on:
            if self.executor.held.get(device, "").startswith(SHED_HOLD):
                del self.executor.held[device]  # the person's switch-off is what holds it now
            self.hold(device, "switched off on the board by a command this daemon did not "
                      "send", by="board")
        elif self.executor.held.get(device, "").startswith(("switched off on the board",
                                                            SHED_HOLD)):
            self.release(device, by="board")

    def _again(self) -> None:
        """A person changed what may be repaired: look at the latest diagnosis again."""
        if self._latest is not None and not self.active:
            self.diagnosed(self._latest)

    async def close(self) -> None:
        for task in (self._pending, self._running):
            if task is not None:
                task.cancel()
                with contextlib.suppress(asyncio.CancelledError, Exception):
                    await task
        sup = self.executor.actuators.supervisor
        if sup is not None:
            await sup.close()


def build(planner: RepairPlanner, model: SystemModel, procs: Mapping[str, ProcessConfig], *,
          observations: ObservationSet, observable: Collection[str], diagnose: FreshDiagnosis,
          emit: Emit, logs_dir: Path, env: Mapping[str, str],
          device_boot_s: Mapping[str, float], on_start: Callable[[str, int], None] | None = None,
          dry_run: bool = False, clock: Callable[[], float] | None = None,
          max_parallel: int | None = None, debounce_s: float = 0.5,
          board: str = "board", confirmed: Confirmed | None = None,
          judge_s: Mapping[str, float] | None = None) -> RepairService:
    """A repair service for a robot: its planner, model and ``processes:`` (see the module
    docstring)."""
    supervisor = ProcessSupervisor(procs, logs_dir, on_start=on_start, env=dict(env))
    actuators = Actuators(model, None, supervisor)
    # on the machine's clock a busy machine stretches a step's time; on a simulated clock
    # nothing real is slow, so nothing is stretched (the daemon passes its clock, the
    # machine's monotonic one unless simulated: the stretch had never reached it)
    kw: dict[str, Any] = {"clock": clock} if clock is not None else {}
    if clock is None or clock is time.monotonic:
        kw["stretch"] = load_stretch
    executor = Executor(
        actuators, ObservedBeliefs(observations),
        settle=settle_times(model, procs, devices=device_boot_s),
        limiter=AttemptLimiter(3, 600.0), dry_run=dry_run, observable=observable,
        max_parallel=max_parallel, judge_s=judge_s, **kw)
    return RepairService(planner, executor, diagnose=diagnose, observations=observations,
                         emit=emit, board=board, debounce_s=debounce_s, confirmed=confirmed)
