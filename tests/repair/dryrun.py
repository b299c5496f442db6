"""The real repair service on the TEDUSAR model in a dry run (plans are made and reported,
nothing acts), for the tests of when a repair starts: ``service_for`` builds it around a given
diagnosis, with the board's own protection idle."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

from host.diagnosis.model import load_system
from host.diagnosis.observations import ObservationSet
from host.diagnosis.result import Diagnosis, DiagnosisResult
from host.events import Event, PlanRecord
from host.repair import service
from host.repair.planner import RepairPlanner
from host.repair.processes import load_processes

TEDUSAR = Path(__file__).resolve().parents[2] / "models" / "tedusar"


def result(*bad: str) -> DiagnosisResult:
    return DiagnosisResult((Diagnosis(frozenset(bad), probability=1.0),), True)


def plans(events: list[Event]) -> list[PlanRecord]:
    return [e for e in events if isinstance(e, PlanRecord)]


async def _idle() -> str:
    return ""


def service_for(tmp: Path, obs: ObservationSet, events: list[Event],
                diagnosis: list[DiagnosisResult], *, debounce_s: float,
                confirmed: Callable[[str], bool]) -> service.RepairService:
    """The service; a fresh diagnosis is ``diagnosis[0]`` (the test may replace it). No board
    link yet (``link``)."""
    model = load_system(TEDUSAR / "system.yaml")

    async def diagnose() -> DiagnosisResult:
        return diagnosis[0]

    svc = service.build(
        RepairPlanner.for_system(TEDUSAR), model, load_processes(TEDUSAR / "system.yaml", model),
        observations=obs, observable=set(), diagnose=diagnose, emit=events.append,
        logs_dir=tmp, env={}, device_boot_s={}, dry_run=True, debounce_s=debounce_s,
        confirmed=confirmed)
    svc._board_busy = _idle  # type: ignore[method-assign]  # the board's protection is idle
    return svc
