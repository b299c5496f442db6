"""A diagnosis that keeps changing is told to the person (issue 11, the campaign's dropout):
the debounce is not weakened — no repair starts on what does not hold — but the component that
keeps entering and leaving the diagnosis is named in one notice per window, on a simulated
clock through the real repair service."""

from __future__ import annotations

import asyncio
from pathlib import Path

from host.diagnosis.model import load_system
from host.diagnosis.observations import ObservationSet
from host.diagnosis.result import Diagnosis, DiagnosisResult
from host.events import Event, Note, describe
from host.repair import service
from host.repair.planner import RepairPlanner
from host.repair.processes import load_processes
from host.repair.unsettled import Unsettled

TEDUSAR = Path(__file__).resolve().parents[2] / "models" / "tedusar"


def result(*bad: str) -> DiagnosisResult:
    return DiagnosisResult((Diagnosis(frozenset(bad), probability=1.0),), True)


def test_a_flipping_diagnosis_is_told_once_per_window_and_no_repair_starts(
        tmp_path: Path) -> None:
    async def main() -> None:
        clock = [100.0]
        model = load_system(TEDUSAR / "system.yaml")
        events: list[Event] = []

        async def diagnose() -> DiagnosisResult:
            return result("hokuyo")

        svc = service.build(
            RepairPlanner.for_system(TEDUSAR), model,
            load_processes(TEDUSAR / "system.yaml", model), observations=ObservationSet(),
            observable=set(), diagnose=diagnose, emit=events.append, logs_dir=tmp_path,
            env={}, device_boot_s={}, dry_run=True, clock=lambda: clock[0],
            debounce_s=3600.0)  # the debounce never ends here: only the notice is tested
        # the lidar's reading drops to 0 mA half of every second: hokuyo in, out, in, ...
        for i in range(30):
            svc.diagnosed(result("hokuyo") if i % 2 == 0 else result())
            clock[0] += 0.5
        told = [e for e in events if isinstance(e, Note)]
        assert len(told) == 2, told  # at 6 changes (2.5 s), again a window (10 s) later
        assert told[0].level == "warning"
        assert describe(told[0]).startswith(
            "warning: hokuyo: diagnosis keeps changing (6 times in 2.5 s)")
        assert not svc.busy  # nothing repaired on a diagnosis that does not hold
        # while a repair runs, its own power cycles and restarts change the diagnosis: untold
        svc._running = asyncio.get_running_loop().create_future()
        for i in range(30):
            svc.diagnosed(result("hokuyo") if i % 2 == 0 else result())
            clock[0] += 0.5
        assert len([e for e in events if isinstance(e, Note)]) == 2
        svc._running.cancel()
        await svc.close()

    asyncio.run(main())


def test_a_steady_fault_or_a_slow_change_is_not_reported() -> None:
    u = Unsettled(window_s=10.0, threshold=6)
    assert u.diagnosed({"hokuyo"}, 0.0) == []
    assert all(u.diagnosed({"hokuyo"}, t) == [] for t in range(1, 60))  # a fault that holds
    out = []
    for i in range(12):  # in and out every 2.5 s: at most 5 changes in any 10 s
        out += u.diagnosed(set() if i % 2 == 0 else {"hokuyo"}, 60.0 + 2.5 * i)
    assert out == []
    flips = []
    for i in range(6):  # then the camera flips fast: only the camera is named
        flips += u.diagnosed({"hokuyo"} | ({"thermal_camera"} if i % 2 == 0 else set()),
                             100.0 + 0.4 * i)
    assert [(f.component, f.changes) for f in flips] == [("thermal_camera", 6)]
