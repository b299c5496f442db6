"""Experiments M2-M4 of MISSIONS.md (plan-execution diagnosis) on the virtual robot.

Each runs the robot's mission (``dxboard mission``) twice, each time on a freshly started
robot with its world: fault-free, then with an event injected through the arena (the pyrobosim
world's ops, ``emulator.robot.world.server``), and reports what the mission layer's
plan-execution diagnosis (``host.plandiag.live``) made of it, with the mission's delay against
the fault-free run:

- **M2 door-closed**: once the robot marks the victim in the office, ``door_office`` falls shut
  behind it. The way out is refused at its precondition check (a propagated fault); the fault
  region is the stretch since the door was last seen open, the diagnosis "door-closes between
  steps i and j" (an exogenous event), the KB corrected, and the new plan opens the door from
  inside and drives out through it (the arena has no second way out of the office).
- **M3 marker-missing**: the marker dispenser jams before the first marking: the action reports
  success, and its expected-state check does not see the marker (a local fault); the action's
  fault mode ``mark-not-placed`` explains it, and the victim is marked again.
- **M4 plan-error**: ``door_office`` is closed and ``door_lab`` locked (the world reports it:
  ``(locked door_lab)``). The robot opens ``door_office`` (an ``open_door`` that works, with
  the door unlocked), then ``open_door(door_lab)`` fails on a robot layer 0 sees healthy and no
  fault mode or event explains it: a plan error, naming the precondition the domain lacks,
  ``(not (locked ?d))`` — the one condition over the action's arguments that held at the
  failure and not at the run that worked; no plan reaches the lab, so the mission stops,
  saying why.

The times of each diagnosis (``diagnoses`` of ``MissionRun``): from the end of the step that
raised the alarm to the ``PlanDiagnosis`` event, and to the first plan made after it.
"""

from __future__ import annotations

import asyncio
import logging
from collections.abc import Awaitable, Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from host.errors import UserError
from host.events import Dispatch
from host.experiment.mission import Injection, MissionRun, run_mission
from host.experiment.session import beside
from host.skills import WorldClient

log = logging.getLogger(__name__)

WORLD_TIMEOUT_S = 10.0


async def world_op(url: str, msg: dict[str, Any], check: Callable[[dict[str, Any]], bool]
                   ) -> None:
    """Send one op to the world and wait until its state passes ``check``."""
    client = await WorldClient.connect(url)
    try:
        await client.send(msg)
        deadline = asyncio.get_running_loop().time() + WORLD_TIMEOUT_S
        while not check(await client.state()):
            if asyncio.get_running_loop().time() > deadline:
                raise UserError(f"the world did not take {msg} within {WORLD_TIMEOUT_S:g} s",
                                "see the emulator's log")
            await asyncio.sleep(0.05)
    finally:
        await client.close()


def _close(door: str, locked: bool | None = None) -> tuple[dict[str, Any],
                                                           Callable[[dict[str, Any]], bool]]:
    msg: dict[str, Any] = {"op": "door", "door": door, "open": False}
    if locked is not None:
        msg["locked"] = locked
    return msg, lambda st: not st["doors"][door] and (
        locked is None or (door in st.get("locked", [])) == locked)


@dataclass(frozen=True)
class PlanScenario:
    name: str
    label: str  # M2, M3, M4
    what: str
    prepare: Callable[[str], Awaitable[None]] | None = None
    trigger: Callable[[Any], bool] | None = None  # the event of the stream to inject at
    during: Callable[[str], Awaitable[None]] | None = None

    def injection(self) -> Injection | None:
        if self.during is None or self.trigger is None:
            return None
        during, trigger = self.during, self.trigger

        async def inject(s: Any, watch: Any, run: MissionRun) -> None:
            await watch.when(trigger)
            await during(s.emulated.urls["world"])
            if watch.t0 is not None:
                run.fault_s = s.daemon.clock() - watch.t0
            log.info("injected: %s", self.what)
        return inject


def _marking_in_office(e: Any) -> bool:
    return isinstance(e, Dispatch) and e.action == "mark_victim" and e.args[-1:] == ("office",)


async def _door_closes(url: str) -> None:
    await world_op(url, *_close("door_office"))


async def _jam(url: str) -> None:
    await world_op(url, {"op": "jam"}, lambda st: True)


async def _lock_lab(url: str) -> None:
    await world_op(url, *_close("door_office"))
    await world_op(url, *_close("door_lab", locked=True))


SCENARIOS = {
    "door-closed": PlanScenario("door-closed", "M2", "door_office closes behind the robot while it "
                            "marks the victim in the office",
                            trigger=_marking_in_office, during=_door_closes),
    "marker-missing": PlanScenario("marker-missing", "M3", "the marker dispenser jams: the first "
                               "marking reports success and leaves nothing", prepare=_jam),
    "plan-error": PlanScenario("plan-error", "M4", "door_office is closed and door_lab locked; "
                           "the domain's open_door ignores locks", prepare=_lock_lab),
}


async def plan_diagnosis(which: str, system_dir: Path, journal: Path, *,
                         timeout_s: float = 300.0, fault_free: bool = True
                         ) -> dict[str, MissionRun]:
    """One of M2-M4: the fault-free mission (unless ``fault_free`` is False), then the one with
    the scenario's event."""

    sc = SCENARIOS[which]
    runs: dict[str, MissionRun] = {}
    if fault_free:
        runs["fault-free"] = await run_mission(system_dir, beside(journal, "fault-free"),
                                               label="fault-free", timeout_s=timeout_s)
    runs[which] = await run_mission(
        system_dir, journal, label=which, timeout_s=timeout_s, prepare=sc.prepare,
        inject=sc.injection())
    return runs


def plan_diagnosis_text(which: str, robot: str, fast: bool, runs: dict[str, MissionRun]
                        ) -> str:
    sc = SCENARIOS[which]
    free, r = runs.get("fault-free"), runs[which]
    lines = [f"experiment {sc.label} ({which}) on {robot}" + (" (fast boot times)" if fast
                                                                else "") + f": {sc.what}", ""]
    for name, run in runs.items():
        state = "completed" if run.completed else f"did not complete: {run.detail}"
        delay = ("" if name == "fault-free" or free is None or free.duration_s is None
                 or run.duration_s is None or not run.completed else
                 f", delay {run.duration_s - free.duration_s:+.1f} s against fault-free")
        lines.append(f"{name:14} {state}: {run.duration_s or 0:.1f} s, {run.actions} actions, "
                     f"{run.replans} replans{delay}")
        lines.append(f"{'':14} journal: {run.journal} (from entry {run.journal_from})")
    if not r.diagnoses:
        lines += ["", "no plan-execution diagnosis was made"]
    for d in r.diagnoses:
        lines += ["", f"plan-execution diagnosis of {d['dispatch_id']} (step {d['step']}, "
                  f"{d['at_s']} s into the mission): {', '.join(d['classes']) or 'unexplained'}",
                  f"  alarm: {d['alarm']}"]
        lines += [f"  {x}" for x in d["symptoms"]]
        if d["region"]:
            lines.append(f"  {d['region']}")
        lines += [f"  {x}" for x in d["histories"][:3]]
        if d["path"]:
            lines.append("  the most probable history, along the context tree:")
            lines += [f"    {x}" for x in d["path"]]
        if d["plan_error"]:
            lines.append(f"  {d['plan_error']}")
        lines += [f"  kb {x}" for x in d["kb"]]
        plan = "; ".join(d["new_plan"] or []) or "(none: the mission stopped)"
        lines.append(f"  new plan: {plan}")
        lines.append(f"  diagnosed {_s(d['to_diagnosis_s'])} after the alarm, new plan "
                     f"{_s(d['to_new_plan_s'])} after it (inference and all: "
                     f"{d['elapsed_s'] * 1000:.1f} ms)")
    return "\n".join(lines)


def _s(x: float | None) -> str:
    return "?" if x is None else f"{x:.3f} s"
