"""Repairs: from a changed diagnosis to verified actions, one repair at a time, never on stale
data.

``Repairs`` is the daemon's bridge to ``host.repair``. It builds, from the robot directory, the
planner (``repair.pddl``), the process supervisor (``processes:`` of ``system.yaml``; every node
it starts gets ``DXBOARD_ZENOH`` — the daemon's topic endpoint — and, with ``--emulate``,
``DXBOARD_DEVICES``), the actuators (board power through the daemon's ``BoardClient``, nodes
through the supervisor), the beliefs the executor waits on (fed with every observer update) and
the ``RepairLoop``.

When a diagnosis changes and names broken components, a repair starts after a short debounce —
unless the board link is down (then every board literal is unknown: nothing to act on), or a
repair is already running (the running loop re-diagnoses after each plan, so it sees the
change). While the board's own protection has the channels (it sheds them for input under-
voltage and restores them itself afterwards), repairs wait for it rather than fight it. The loop
diagnoses, chooses, plans, executes with verified effects and repeats until healthy, bounded by
the executor's attempt limiter and quarantine. Every plan, action and quarantine is journaled
and shown on the page; with ``--dry-run`` plans are made and reported but nothing acts. Device
settle times are their boot times, from the robot's ``emulator.yaml`` (``boot_ms``, the real
devices' figures) when it has one.
"""

from __future__ import annotations

import asyncio
import contextlib
import logging
from collections import Counter
from collections.abc import Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

import yaml

from host.diagnosis import DiagnosisResult
from host.diagnosis.logic import Literal
from host.journal import Note, PlanRecord
from host.observers.base import Update
from host.repair import Candidate, RepairPlanner
from host.repair.actuators import Actuators
from host.repair.beliefs import ObservedBeliefs
from host.repair.executor import Event, Executor, StepReport
from host.repair.limits import AttemptLimiter, Quarantined
from host.repair.loop import LoopOutcome, RepairLoop
from host.repair.processes import load_processes
from host.repair.supervisor import ProcessSupervisor
from host.web.status import RepairStatus
from protocol.constants import B_UV_OFF, B_UV_SHED, F_SHED_UV

if TYPE_CHECKING:
    from host.daemon.core import Daemon

log = logging.getLogger(__name__)

RECENT_ACTIONS = 30
BOARD_POLL_S = 0.5


class Repairs:
    def __init__(self, daemon: Daemon) -> None:
        from host.repair.effects import settle_times

        self.daemon = daemon
        opts = daemon.opts
        model = daemon.model
        self.planner = RepairPlanner.for_system(opts.system_dir)
        procs = load_processes(opts.system_dir, model)
        journal = opts.journal or Path("dxboard-journal.sqlite")
        env = {"DXBOARD_ZENOH": daemon.observers_cfg.source.listen[0], **opts.node_env}
        self.supervisor = ProcessSupervisor(
            procs, journal.parent / (journal.stem + "-logs"), on_start=self._started, env=env)
        self.actuators = Actuators(model, None, self.supervisor)
        self.beliefs = ObservedBeliefs()
        observable = {a for o in daemon.hub.observers for a in o.atoms()}
        self.executor = Executor(
            self.actuators, self.beliefs,
            settle=settle_times(model, procs, devices=device_boot_s(opts.system_dir)),
            limiter=AttemptLimiter(3, 600.0), report=self._report, dry_run=opts.dry_run,
            observable=observable, clock=daemon.clock, max_parallel=opts.max_parallel_steps)
        self.loop = RepairLoop(self.planner, self.executor, self._diagnose,
                               on_plan=self._plan)
        self._pending: asyncio.Task[Any] | None = None
        self._running: asyncio.Task[Any] | None = None
        self._actions: dict[str, RepairStatus] = {}  # by action id, oldest first
        self._outcomes: Counter[str] = Counter()

    # --- wiring -------------------------------------------------------------------------

    def _started(self, node: str, pid: int) -> None:
        watcher = self.daemon.hub.watcher
        if watcher is not None:
            watcher.track(node, pid)

    def observed(self, updates: list[Update]) -> None:
        self.beliefs.update(updates)

    # --- triggering ---------------------------------------------------------------------

    def diagnosis_changed(self, result: DiagnosisResult) -> None:
        if self._pending is not None:
            self._pending.cancel()
            self._pending = None
        if self.daemon.healthy() or self.busy:
            return  # nothing to do, or the running loop re-diagnoses by itself
        self._pending = asyncio.ensure_future(self._after_debounce(result))

    @property
    def busy(self) -> bool:
        """A repair is running."""
        return self._running is not None and not self._running.done()

    @property
    def active(self) -> bool:
        """A repair is running or about to start (its debounce is pending)."""
        return self.busy or (self._pending is not None and not self._pending.done())

    async def _after_debounce(self, result: DiagnosisResult) -> None:
        await asyncio.sleep(self.daemon.opts.repair_debounce_s)
        now = self.daemon.result
        if now is None or now.bad_sets() != result.bad_sets() or self.busy:
            return  # superseded
        if not self.daemon.link_up or self.daemon.client is None:
            self.daemon.record(Note("no repair while the board link is down"))
            return
        self._running = asyncio.ensure_future(self._repair())

    async def _board_busy(self) -> str:
        """Why the board's own protection has the channels now (empty: it has not).

        Under input under-voltage the board sheds channels, refuses to switch them on and
        restores them itself, spaced, once the voltage is back: a repair would fight it and
        spend the devices' attempts on refusals. So repairs wait until the board is done."""
        client = self.daemon.client
        if client is None:
            return "the board link is down"
        state = await client.state()
        if state.board_flags & (B_UV_SHED | B_UV_OFF):
            return "the board sheds channels for input under-voltage"
        shed = [c.name for c in state.channels if c.live_faults & F_SHED_UV]
        if shed:
            return f"the board is restoring {', '.join(shed)} after an under-voltage"
        return ""

    async def _wait_for_board(self) -> None:
        """Wait (noting why, once) while the board's own protection has the channels."""
        said = ""
        while reason := await self._board_busy():
            if reason != said:
                self.daemon.record(Note(f"repairs wait: {reason}"))
                said = reason
            await asyncio.sleep(BOARD_POLL_S)

    async def _repair(self) -> None:
        await self._wait_for_board()
        self.actuators.board = self.daemon.client
        res = await self.loop.run()
        self._outcomes[str(res.outcome)] += 1
        level = "info" if res.outcome is LoopOutcome.HEALTHY else "warning"
        self.daemon.record(Note(f"repair ended: {res.outcome} after {len(res.rounds)} "
                                f"round(s)", level))
        self.daemon.status.update(repairs_by_outcome=dict(self._outcomes))

    async def _diagnose(self) -> tuple[Sequence[Candidate], Sequence[Literal]]:
        """The loop's view: a fresh diagnosis of what is observed now."""
        if not self.daemon.link_up:  # board literals are unknown: only the link is to blame
            link = Candidate(frozenset({self.daemon.model.board or "board"}), 1.0)
            return [link], self.daemon.diagnoser.observations.literals()
        await self._wait_for_board()
        result = self.daemon.diagnose("repair")
        cands = [Candidate(frozenset(d.bad), d.probability) for d in result.diagnoses]
        return cands, self.daemon.diagnoser.observations.literals()

    # --- reporting ----------------------------------------------------------------------

    def _plan(self, record: PlanRecord) -> None:
        self.daemon.record(record)
        if self.daemon.opts.dry_run:
            self.daemon.record(Note(f"dry run: plan {record.plan_id} not carried out"))

    def _report(self, event: Event) -> None:
        if isinstance(event, StepReport):
            self.daemon.record(event.to_record())
            self._actions.pop(event.action_id, None)
            self._actions[event.action_id] = RepairStatus(
                event.step.action, tuple(event.step.args), str(event.state),
                self._wall(event.started), self._wall(event.finished))
            while len(self._actions) > RECENT_ACTIONS:
                del self._actions[next(iter(self._actions))]
            self.daemon.status.update(repairs=tuple(self._actions.values()),
                                      updated=self.daemon.wall())
        elif isinstance(event, Quarantined):
            self.daemon.record(Note(
                f"quarantined {event.component}: {event.reason}; safe state "
                f"{event.safe_state or 'as it was'}; clear it by hand to repair it again",
                "warning"))

    def _wall(self, mono: float | None) -> float | None:
        """A time of the daemon's monotonic clock as wall time (the page shows wall times)."""
        if mono is None:
            return None
        return self.daemon.wall() - (self.daemon.clock() - mono)

    async def close(self) -> None:
        for task in (self._pending, self._running):
            if task is not None:
                task.cancel()
                with contextlib.suppress(asyncio.CancelledError, Exception):
                    await task
        await self.supervisor.close()


def device_boot_s(system_dir: Path) -> dict[str, float]:
    """Each device's boot time in seconds, from the robot's ``emulator.yaml`` if it has one."""
    path = system_dir / "emulator.yaml"
    try:
        data = yaml.safe_load(path.read_text())
    except (OSError, yaml.YAMLError):
        return {}
    out: dict[str, float] = {}
    for ch in (data or {}).get("channels", []) if isinstance(data, dict) else []:
        if isinstance(ch, dict) and isinstance(ch.get("boot_ms"), int | float):
            out[str(ch.get("name"))] = float(ch["boot_ms"]) / 1000.0
    return out
