"""Missions on the virtual robot: one run of the layered robot (``dxboard mission``) and
experiment M1 (``dxboard experiment mission-fault``, MISSIONS.md).

``run_mission(system_dir, journal)`` starts the emulated robot with its world (``dxboard
emulate --robot --world``) and the daemon through ``host.launch`` (``RobotSession``), waits until
layer 0 has brought the robot up (all-normal), wires layers 1-3 to the daemon
(``host.launch.mission_stack``) and runs the mission, every event on the daemon's stream and in its
journal. ``prepare`` sets the world up before the mission (given its URL), ``inject`` runs
beside the mission (M2-M4: ``host.experiment.plandiag``). With ``fault`` the Hokuyo hangs
(``dxboard inject hokuyo hang``) ``FAULT_DELAY_S`` into the
mission's first navigation: layer 0 diagnoses and repairs it while the tree's guard
holds the navigation. With ``flat`` the mission runs without the layers' hand-over (skills
that abort once their inputs stop, trees without guards or retries, a planner blind to layer 0), the
baseline that aborts the action and replans. ``on_event`` sees every stamped event (the
terminal's lines).

``MissionRun`` says how it went: completed or not and why, its duration from the first
dispatch to the end, the actions dispatched, replans, when the fault came and when layer 0's
repair of the lidar began and ended (seconds since the mission started; a busy machine may
make layer 0 repair other things too, which the journal shows), the failures that reached the
mission layer, and the journal's range.
"""

from __future__ import annotations

import asyncio
import contextlib
import logging
from collections.abc import Awaitable, Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from host.errors import UserError
from host.events import (
    Dispatch,
    LayerResult,
    MissionState,
    PlanDiagnosis,
    PlanRecord,
    RepairEnded,
    Stamped,
    TreeChange,
)
from host.experiment.session import RobotSession, beside
from host.launch.mission_stack import MissionStack
from host.layers import MISSION

log = logging.getLogger(__name__)

Injection = Callable[[RobotSession, "_Watch", "MissionRun"], Awaitable[None]]

FAULT_DEVICE = "hokuyo"
FAULT_DELAY_S = 1.5  # into the first navigation, the lidar hangs


@dataclass
class MissionRun:
    label: str
    completed: bool = False
    detail: str = ""
    components: list[str] = field(default_factory=list)
    duration_s: float | None = None
    actions: int = 0
    replans: int = 0
    fault_s: float | None = None
    repair_start_s: float | None = None
    repair_end_s: float | None = None
    holds: int = 0
    mission_failures: list[str] = field(default_factory=list)
    journal: str = ""
    journal_from: int | None = None
    diagnoses: list[dict[str, Any]] = field(default_factory=list)  # plan-execution diagnoses

    def to_json(self) -> dict[str, Any]:
        def r(x: float | None) -> float | None:
            return None if x is None else round(x, 2)

        return {"label": self.label, "completed": self.completed, "detail": self.detail,
                "components": self.components, "duration_s": r(self.duration_s),
                "actions": self.actions, "replans": self.replans, "fault_s": r(self.fault_s),
                "repair_start_s": r(self.repair_start_s), "repair_end_s": r(self.repair_end_s),
                "holds": self.holds, "mission_failures": self.mission_failures,
                "journal": self.journal, "journal_from": self.journal_from,
                "diagnoses": self.diagnoses}


class _Watch:
    """A reader of the daemon's stream: what the run reports, on the daemon's clock."""

    def __init__(self, run: MissionRun, on_event: Callable[[Stamped], None] | None) -> None:
        self.run = run
        self.on_event = on_event
        self.t0: float | None = None
        self.driving = asyncio.Event()
        self.alarm: float | None = None  # when the last mission action ended (not as planned)
        self.waiters: list[tuple[Callable[[Any], bool], asyncio.Future[None]]] = []

    def when(self, test: Callable[[Any], bool]) -> asyncio.Future[None]:
        """Done once an event of the stream passes ``test``."""
        fut: asyncio.Future[None] = asyncio.get_running_loop().create_future()
        self.waiters.append((test, fut))
        return fut

    def __call__(self, s: Stamped) -> None:
        e, run = s.event, self.run
        match e:
            case Dispatch() if self.t0 is None:
                self.t0 = s.mono
            case TreeChange(status="RUNNING") if e.node.startswith("navigate(") \
                    and self.t0 is not None:
                self.driving.set()
            case TreeChange(status="RUNNING") if e.detail.startswith("holding") \
                    and e.previous != "RUNNING":
                run.holds += 1  # a hold begins
            case PlanRecord() if self.t0 is not None and run.repair_start_s is None \
                    and FAULT_DEVICE in {a for st in e.steps for a in st.args}:
                run.repair_start_s = s.mono - self.t0  # layer 0 repairs the lidar
            case RepairEnded() if run.repair_start_s is not None and run.repair_end_s is None:
                run.repair_end_s = s.mono - (self.t0 or s.mono)
            case LayerResult(layer=layer, success=False) if layer == MISSION:
                run.mission_failures.append(f"{e.command}({', '.join(e.args)})")
                self.alarm = s.mono
            case MissionState(state="replanning"):
                run.replans += 1
            case PlanDiagnosis():
                after = None if self.alarm is None else round(s.mono - self.alarm, 3)
                run.diagnoses.append({**e.to_json(), "to_diagnosis_s": after,
                                      "to_new_plan_s": None, "new_plan": None,
                                      "at_s": None if self.t0 is None
                                      else round(s.mono - self.t0, 2)})
            case MissionState(state="planned") if run.diagnoses \
                    and run.diagnoses[-1]["new_plan"] is None:
                d = run.diagnoses[-1]
                d["new_plan"] = [str(p) for p in e.plan]
                d["to_new_plan_s"] = None if self.alarm is None else round(s.mono - self.alarm, 3)
        for test, fut in list(self.waiters):
            if not fut.done() and test(e):
                fut.set_result(None)
        if self.on_event is not None:
            self.on_event(s)


async def run_mission(system_dir: Path, journal: Path, *, label: str = "mission",
                      fault: bool = False, flat: bool = False, timeout_s: float = 300.0,
                      web: tuple[str, int] | None = None,
                      on_event: Callable[[Stamped], None] | None = None,
                      on_ready: Callable[[RobotSession], None] | None = None,
                      prepare: Callable[[str], Awaitable[None]] | None = None,
                      inject: Injection | None = None,
                      on_step: Callable[[str], None] | None = None) -> MissionRun:
    """Start the robot, wait until layer 0 has it healthy, run the mission. ``on_step`` is told
    as each step that may take seconds begins (a person watching sees progress, not silence);
    ``on_event`` gets the daemon's events from the bring-up on."""
    step = on_step or (lambda text: None)
    run = MissionRun(label, journal=str(journal))
    step("starting the emulated robot, its world and the daemon")
    async with RobotSession(system_dir, journal, emulate_args=("--world",), web=web) as s:
        if on_ready is not None:
            on_ready(s)
        step("waiting until layer 0 has brought the robot up (healthy for 2 s)")
        bring_up = s.daemon.subscribe(on_event) if on_event is not None else (lambda: None)
        try:
            healthy = await s.wait_healthy(timeout_s, hold_s=2.0)
        finally:
            bring_up()
        if not healthy:
            raise UserError(f"{label}: the robot did not come up within {timeout_s:g} s",
                            f"see the journal: dxboard journal {journal}")
        step("the robot is healthy: starting the mission's layers (skills, executive, "
             "planner)")
        world = s.emulated.urls.get("world")
        if world is None:
            raise UserError(f"{system_dir}: the emulated robot serves no world",
                            "give a robot with an arena (SYSTEM_DIR/arena/world.yaml)")
        if prepare is not None:
            await prepare(world)  # the world as the experiment wants it before the mission
        run.journal_from = await s.last_id() + 1
        watch = _Watch(run, on_event)
        unsubscribe = s.daemon.subscribe(watch)
        stack = await MissionStack.start(s.daemon, world, system_dir, flat=flat)
        step("running the mission")
        if fault:
            inject = _inject
        injector = None if inject is None else asyncio.ensure_future(inject(s, watch, run))
        try:
            outcome = await asyncio.wait_for(stack.run(), timeout_s)
        except TimeoutError:
            raise UserError(f"{label}: the mission did not end within {timeout_s:g} s",
                            f"see the journal: dxboard journal {journal}") from None
        finally:
            if injector is not None:
                injector.cancel()
                with contextlib.suppress(asyncio.CancelledError):
                    await injector
            await stack.close()
            unsubscribe()
        end = s.daemon.clock()
        run.completed, run.detail = outcome.completed, outcome.detail
        run.components, run.actions = list(outcome.components), outcome.actions
        run.duration_s = None if watch.t0 is None else end - watch.t0
    return run


async def _inject(s: RobotSession, watch: _Watch, run: MissionRun) -> None:
    """Hang the lidar once the robot is well into a navigation."""
    await watch.driving.wait()
    await asyncio.sleep(FAULT_DELAY_S)  # a scenario's moment, not a wait for a condition
    await s.inject(FAULT_DEVICE, "hang")
    if watch.t0 is not None:
        run.fault_s = s.daemon.clock() - watch.t0
    log.info("injected: %s hangs", FAULT_DEVICE)


async def mission_fault(system_dir: Path, journal: Path, *, timeout_s: float = 300.0,
                        fault_free: bool = True) -> dict[str, MissionRun]:
    """M1: fault-free (unless ``fault_free`` is False), the lidar hang on the layered robot,
    the same on the flat system."""

    runs: dict[str, MissionRun] = {}
    if fault_free:
        runs["fault-free"] = await run_mission(system_dir, beside(journal, "fault-free"),
                                               label="fault-free", timeout_s=timeout_s)
    runs["layered"] = await run_mission(system_dir, journal, label="layered", fault=True,
                                        timeout_s=timeout_s)
    runs["flat"] = await run_mission(system_dir, beside(journal, "flat"), label="flat",
                                     fault=True, flat=True, timeout_s=timeout_s)
    return runs


def mission_fault_text(robot: str, fast: bool, runs: dict[str, MissionRun]) -> str:
    free = runs.get("fault-free")
    base = None if free is None else free.duration_s
    lines = [f"experiment M1 (mission-fault) on {robot}"
             + (" (fast boot times)" if fast else "")
             + f": {FAULT_DEVICE} hangs {FAULT_DELAY_S:g} s into the first navigation", ""]
    for name, r in runs.items():
        state = "completed" if r.completed else f"did not complete: {r.detail}"
        delay = ("" if base is None or r.duration_s is None or name == "fault-free"
                 or not r.completed
                 else f", delay {r.duration_s - base:+.1f} s against fault-free")
        lines.append(f"{name:10} {state}: {r.duration_s or 0:.1f} s, {r.actions} actions, "
                     f"{r.replans} replans{delay}")
        if r.fault_s is not None:
            rep = ("" if r.repair_start_s is None else
                   f"; layer 0 repaired from {r.repair_start_s:.1f} s to "
                   + ("?" if r.repair_end_s is None else f"{r.repair_end_s:.1f} s"))
            lines.append(f"{'':10} fault at {r.fault_s:.1f} s{rep}; guard holds: {r.holds}; "
                         f"failures at the mission layer: "
                         f"{', '.join(r.mission_failures) or 'none'}")
        lines.append(f"{'':10} journal: {r.journal} (from entry {r.journal_from})")
    lay, flat = runs["layered"].duration_s, runs["flat"].duration_s
    if lay is not None and flat is not None and runs["layered"].completed \
            and runs["flat"].completed:
        when = "before" if flat >= lay else "after"
        lines += ["", f"the layered robot finished {abs(flat - lay):.1f} s {when} the flat "
                      "system"]
    return "\n".join(lines)
