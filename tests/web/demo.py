"""Realistic data for the web tests: the TEDUSAR robot a few seconds into a repair.

Ten board channels as ``models/tedusar/system.yaml`` assigns them, the jaguar base just
powered back up (the device-shut-down scenario of paper 000 §VI, figure 6), its driver still
diagnosed broken, and a two-step plan half done. ``demo_status(now)`` builds the snapshot with
times relative to ``now``; ``demo_journal(journal, now)`` writes the matching history.
``kept_fresh(source)`` keeps the snapshot's time current while a test runs, as a running
daemon's channel samples do, so that a browser slow to start on a busy machine does not find
the demo's data stale.
"""

from __future__ import annotations

import asyncio
import contextlib
import math
import time
from collections.abc import AsyncIterator

from host.journal import (
    ActionRecord,
    ActionState,
    BoardEvent,
    DiagnosisRecord,
    Journal,
    Observation,
    PlanRecord,
    PlanStep,
)
from host.web import ChannelView, DiagnosisStatus, MemoryStatusSource, RepairStatus, Status

CHANNELS = [  # id, name, state, current in mA
    (0, "sensor_head", "on", 820.0), (1, "laser_alignment", "on", 310.0), (2, "pc", "on", 3900.0),
    (3, "hokuyo", "on", 640.0), (4, "kinect", "off", 0.0), (5, "router", "on", 450.0),
    (6, "thermal_camera", "tripped", 0.0), (7, "jaguar", "inrush", 7400.0),
    (8, "spare8", "off", 0.0), (9, "spare9", "latched", 0.0),
]

OBSERVATIONS: dict[str, bool | None] = {
    "ok(hokuyo_node)": True, "ok(imu_node)": True, "ok(jaguar_node)": False,
    "ok(laser_alignment_node)": True, "running(jaguar_node)": True, "on(jaguar)": True,
    "current_ok(jaguar)": None, "current_ok(hokuyo)": True, "ok(joy_node)": True,
    "ok(hector_mapping)": True, "ok(jaguar_teleop_node)": False,
}


def _history(ma: float, seed: int, n: int = 120) -> tuple[float, ...]:
    if ma == 0:
        return (0.0,) * n
    return tuple(round(ma * (1 + 0.06 * math.sin(i / 5 + seed) + 0.03 * math.sin(i * 1.7)), 1)
                 for i in range(n))


def demo_status(now: float) -> Status:
    channels = tuple(
        ChannelView(cid, name, state in ("on", "inrush"), state, ma, _history(ma, cid))
        for cid, name, state, ma in CHANNELS)
    return Status(
        channels=channels,
        observations=dict(OBSERVATIONS),
        diagnoses=(DiagnosisStatus(("jaguar_node",), 0.71),
                   DiagnosisStatus(("jaguar_teleop_node", "jaguar_node"), 0.29)),
        diagnosis_complete=True,
        repairs=(RepairStatus("power_up", ("jaguar",), "succeeded", now - 9.0, now - 7.4),
                 RepairStatus("stop_node", ("jaguar_node",), "succeeded", now - 6.0, now - 5.2),
                 RepairStatus("start_node", ("jaguar_node",), "started", now - 4.0, None)),
        board_link_up=True, updated=now, robot="tedusar",
        observation_changes=57, diagnosis_runs=12, diagnosis_latency_sum_s=0.084,
        diagnosis_last_latency_s=0.006, repairs_by_outcome={"succeeded": 5, "failed": 1})


def demo_journal(journal: Journal, now: float) -> None:
    t = now - 12.0
    items = [
        BoardEvent("state", 7, {"old": "on", "new": "off"}),
        Observation("ok(jaguar_node)", False, "topic:/odom"),
        Observation("on(jaguar)", False, "board"),
        DiagnosisRecord.of([["jaguar", "jaguar_node"]], trigger="observation", elapsed_s=0.005),
        PlanRecord("p1", (PlanStep("power_up", ("jaguar",)),), ("jaguar",)),
        ActionRecord("a1", "power_up", ("jaguar",), ActionState.STARTED, now - 9.0),
        ActionRecord("a1", "power_up", ("jaguar",), ActionState.SUCCEEDED, now - 9.0, now - 7.4),
        Observation("on(jaguar)", True, "board"),
        DiagnosisRecord.of([["jaguar_node"], ["jaguar_teleop_node", "jaguar_node"]],
                           trigger="observation", elapsed_s=0.006),
        PlanRecord("p2", (PlanStep("stop_node", ("jaguar_node",)),
                          PlanStep("start_node", ("jaguar_node",))), ("jaguar_node",)),
        ActionRecord("a2", "stop_node", ("jaguar_node",), ActionState.STARTED, now - 6.0),
        ActionRecord("a2", "stop_node", ("jaguar_node",), ActionState.SUCCEEDED, now - 6.0,
                     now - 5.2),
        ActionRecord("a3", "start_node", ("jaguar_node",), ActionState.STARTED, now - 4.0),
    ]
    for i, payload in enumerate(items):
        journal.record(payload, wall=t + i * 0.7, mono=1000.0 + i * 0.7)
    journal.flush_blocking(timeout=10)


@contextlib.asynccontextmanager
async def kept_fresh(source: MemoryStatusSource, every_s: float = 0.5) -> AsyncIterator[None]:
    """While inside, the status's ``updated`` is now (refreshed every ``every_s``)."""
    async def touch() -> None:
        while True:
            source.update(updated=time.time())
            await asyncio.sleep(every_s)

    task = asyncio.create_task(touch())
    try:
        yield
    finally:
        task.cancel()
        with contextlib.suppress(asyncio.CancelledError):
            await task
