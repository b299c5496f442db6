"""The mission stack over a real world, in one process: the seam where layer 0 enters is the test.

``Harness`` serves the real pyrobosim arena of ``models/tedusar`` with the world's real skill
servers (``emulator.robot.world.server``) on a free port, on a clock ``SPEED`` times faster than
the host's (so a mission takes seconds), with the board's truth given by the test
(``GivenTruth``: what blocks the base, the lidar, the camera or the mount). Layer 0 is what the
test says on the event stream: ``Layer0View`` is fed real ``host.events`` values (a diagnosis, a
repair's plan and end, a quarantine), exactly what the daemon emits. Every event of the layers
is kept in ``events``.
"""

from __future__ import annotations

import asyncio
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

from emulator.robot.world.arena import load_arena
from emulator.robot.world.server import WorldServer
from host.events import (
    ActionRecord,
    ActionState,
    DiagnosisRecord,
    Event,
    PlanRecord,
    PlanStep,
    QuarantineChange,
    RepairEnded,
    Stamped,
)
from host.launch.mission_stack import wire
from host.mission.files import MissionFiles, load_mission
from host.mission.runner import MissionRunner
from host.skills import Layer0View, WorldClient

TEDUSAR = Path(__file__).resolve().parents[2] / "models" / "tedusar"
SPEED = 4.0


class GivenTruth:
    def __init__(self) -> None:
        self.blocked_by: dict[str, str] = {}

    def blocked(self, need: str) -> str | None:
        return self.blocked_by.get(need)


class Harness:
    def __init__(self) -> None:
        self.truth = GivenTruth()
        self.t0 = time.monotonic()
        self.world = WorldServer(load_arena(TEDUSAR), self.truth, self.now_ms)
        self.layer0 = Layer0View()
        self.events: list[Event] = []
        self.files: MissionFiles = load_mission(TEDUSAR)
        self.client: WorldClient | None = None

    def now_ms(self) -> int:
        return int((time.monotonic() - self.t0) * 1000 * SPEED)

    @staticmethod
    def clock() -> float:
        return time.monotonic()

    def emit(self, event: Event) -> None:
        self.events.append(event)

    async def start(self) -> WorldClient:
        self.client = await WorldClient.connect(await self.world.start())
        return self.client

    async def close(self) -> None:
        if self.client is not None:
            await self.client.close()
        await self.world.stop()

    def runner(self, flat: bool = False) -> MissionRunner:
        assert self.client is not None
        return wire(self.files, self.client, self.layer0, self.clock, self.emit, flat=flat)

    # --- layer 0, as the daemon says it ---------------------------------------------------
    def say(self, event: Event) -> None:
        self.layer0(Stamped(time.time(), self.clock(), event))

    def repairing(self, component: str) -> None:
        self.say(DiagnosisRecord(((component,),)))
        self.say(PlanRecord("p1", (PlanStep("power_cycle", (component,)),), (component,)))
        self.say(ActionRecord("a1", "power_cycle", (component,), ActionState.STARTED,
                              self.clock()))

    def repaired(self) -> None:
        self.say(ActionRecord("a1", "power_cycle", (), ActionState.SUCCEEDED, self.clock(),
                              self.clock()))
        self.say(RepairEnded("repaired", 1))
        self.say(DiagnosisRecord(((),)))

    def quarantine(self, component: str) -> None:
        self.say(QuarantineChange(component, True, "3 repairs did not hold"))

    def of(self, cls: type[Any]) -> list[Any]:
        return [e for e in self.events if isinstance(e, cls)]


async def until(cond: Callable[[], bool], what: str, timeout: float = 60.0) -> None:
    """Wait for ``cond`` (polling), failing with ``what`` after a generous deadline."""
    deadline = time.monotonic() + timeout
    while not cond():
        if time.monotonic() > deadline:
            raise AssertionError(f"timed out waiting for {what}")
        await asyncio.sleep(0.05)
