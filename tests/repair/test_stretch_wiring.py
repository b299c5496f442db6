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


def test_a_device_boots_in_its_own_time_a_process_starts_slower(tmp_path: Path) -> None:
    """Stretched three times over, a driver's start gets three times its settle; a device's
    power-up and power cycle keep theirs (its boot does not wait for the computer), so a busy
    robot does not wait three times a lidar's boot before it looks."""
    from host.planning.plan import Step

    ex = built(tmp_path, time.monotonic).executor
    start = Step(0, "start_node", ("hokuyo_node",))
    up, cycle = Step(0, "power_up", ("hokuyo",)), Step(0, "power_cycle", ("hokuyo",))
    assert ex.settle_of(start) > 0 and ex.settle_of(up) > 0
    assert ex.stretched_settle(start, 3.0) == 3.0 * ex.settle_of(start)
    assert ex.stretched_settle(up, 3.0) == ex.settle_of(up)
    assert ex.stretched_settle(cycle, 3.0) == ex.settle_of(cycle)
