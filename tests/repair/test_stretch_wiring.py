"""The daemon's repairs get the busy machine's stretch: ``service.build`` stretches a step's
time on the machine's monotonic clock (what the daemon passes) and on none, never on a
simulated clock. Before, any clock turned it off, and the daemon always passes one: a start
judged in an unstretched 12 s at a load of 20 restarted a healthy hector_mapping."""

from __future__ import annotations

import time
from pathlib import Path

from host.diagnosis.model import load_system
from host.diagnosis.observations import ObservationSet
from host.diagnosis.result import DiagnosisResult
from host.repair import service
from host.repair.executor import load_stretch
from host.repair.planner import RepairPlanner
from host.repair.processes import load_processes

TEDUSAR = Path(__file__).resolve().parents[2] / "models" / "tedusar"


def built(tmp: Path, clock: object) -> service.RepairService:
    model = load_system(TEDUSAR / "system.yaml")

    async def diagnose() -> DiagnosisResult:
        return DiagnosisResult((), True)

    kw = {} if clock is None else {"clock": clock}
    return service.build(
        RepairPlanner.for_system(TEDUSAR), model, load_processes(TEDUSAR / "system.yaml", model),
        observations=ObservationSet(), observable=set(), diagnose=diagnose, emit=lambda e: None,
        logs_dir=tmp, env={}, device_boot_s={}, dry_run=True, **kw)  # type: ignore[arg-type]


def test_the_machines_clock_is_stretched_a_simulated_one_never(tmp_path: Path) -> None:
    assert built(tmp_path, time.monotonic).executor.stretch is load_stretch  # the daemon's
    assert built(tmp_path, None).executor.stretch is load_stretch
    simulated = [0.0]
    assert built(tmp_path, lambda: simulated[0]).executor.stretch() == 1.0
