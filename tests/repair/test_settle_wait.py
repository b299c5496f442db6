"""The repair service waits for what has just come up, spares a device the board restored,
and spends no attempt on a brown-out (issue 25, item 7), without timing luck: the real service
of the tedusar robot (``tests/repair/test_shed.py``'s harness), its observations set by the test.

End to end (with timing): ``tests/daemon/test_false_repairs.py``, ``test_restart_settle.py``.
"""

from __future__ import annotations

import asyncio
import dataclasses
import time
from pathlib import Path

from host.diagnosis.model import load_system
from host.diagnosis.observations import Observation, ObservationSet
from host.diagnosis.result import Diagnosis, DiagnosisResult
from host.events import Event, Note
from host.repair import service
from host.repair.planner import RepairPlanner
from host.repair.processes import load_processes
from protocol.constants import F_SHED_UV
from tests.repair.test_shed import TEDUSAR, Board, board

JAGUAR = 7


def make(tmp_path: Path) -> tuple[service.RepairService, list[Event]]:
    model = load_system(TEDUSAR / "system.yaml")
    events: list[Event] = []

    async def diagnose() -> DiagnosisResult:  # the base or its driver: /odom is silent
        return DiagnosisResult((Diagnosis(frozenset({"jaguar"}), probability=0.67),
                                Diagnosis(frozenset({"jaguar_node"}), probability=0.33)), True)

    svc = service.build(
        RepairPlanner.for_system(TEDUSAR), model,
        load_processes(TEDUSAR / "system.yaml", model), observations=ObservationSet(),
        observable=set(), diagnose=diagnose, emit=events.append, logs_dir=tmp_path, env={},
        device_boot_s={"jaguar": 0.3}, dry_run=True)
    svc.link(Board(board(set())))  # type: ignore[arg-type]
    return svc, events


def test_a_node_just_started_is_given_its_settle_time(tmp_path: Path) -> None:
    async def main() -> None:
        svc, events = make(tmp_path)
        started = time.monotonic()
        svc.observations.add(Observation.parse("running(jaguar_node)", started))
        await svc._wait_for_board()
        settle = svc.executor.settle["jaguar_node"]
        assert time.monotonic() >= started + settle  # not judged before its settle time
        assert any(isinstance(e, Note) and "jaguar_node just came up: booting" in e.text
                   for e in events), events
        await svc.close()

    asyncio.run(main())


def test_a_device_on_without_a_switch_on_of_ours_is_not_blamed(tmp_path: Path) -> None:
    async def main() -> None:
        svc, events = make(tmp_path)
        booted = time.monotonic() - 1.0  # came on a second ago, booted in 0.3 s
        svc.observations.add(Observation.parse("on(jaguar)", booted))
        cands, _ = await svc._diagnose()
        assert [set(c.bad) for c in cands] == [{"jaguar_node"}]  # its driver, not the base
        assert any(isinstance(e, Note) and e.text.startswith("jaguar: came on without a repair")
                   for e in events)
        # switched on by this host: then the base may be to blame as before
        svc.executor.actuators.commands.append((booted - 0.1, JAGUAR, True))
        cands, _ = await svc._diagnose()
        assert [set(c.bad) for c in cands] == [{"jaguar"}, {"jaguar_node"}]
        await svc.close()

    asyncio.run(main())


def test_a_brownout_spends_no_repair_attempt(tmp_path: Path) -> None:
    async def main() -> None:
        svc, _ = make(tmp_path)
        lim, now = svc.executor.limiter, time.monotonic()
        for _ in range(2):  # its bring-up (free), then a driver restart that worked
            lim.record("jaguar_node", now)
            lim.verified("jaguar_node", now)
        assert lim.count("jaguar_node", now) == 1
        state = board(set())
        chans = tuple(dataclasses.replace(c, physical=False, current_ma=0,
                                          live_faults=F_SHED_UV, sticky_faults=F_SHED_UV)
                      if c.channel == JAGUAR else c for c in state.channels)
        svc.link(Board(dataclasses.replace(state, channels=chans)))  # type: ignore[arg-type]
        assert "restoring jaguar" in await svc._board_busy()
        assert lim.count("jaguar_node", now) == 0
        await svc.close()

    asyncio.run(main())


def test_a_restored_device_is_spared_once_then_blamed_again(tmp_path: Path) -> None:
    """Found in the suite (test_repairs, permanent hang, right after the board's reset test):
    the lidar hung seconds after the board had restored it; it was spared, its driver
    restarted twice, and the driver quarantined while the lidar stayed hung. Spared once: if
    restarting the driver did not do it, the device is blamed again."""
    async def main() -> None:
        svc, _ = make(tmp_path)
        svc.observations.add(Observation.parse("on(jaguar)", time.monotonic() - 1.0))
        first, _ = await svc._diagnose()
        assert [set(c.bad) for c in first] == [{"jaguar_node"}]  # its driver first
        again, _ = await svc._diagnose()  # the driver's restart did not do it
        assert [set(c.bad) for c in again] == [{"jaguar"}, {"jaguar_node"}]
        svc.observations.add(Observation.parse("on(jaguar)", time.monotonic() - 0.5))
        svc.observations.add(Observation.parse("~on(jaguar)", time.monotonic() - 0.4))
        svc.observations.add(Observation.parse("on(jaguar)", time.monotonic() - 0.3))
        fresh, _ = await svc._diagnose()  # restored once more by the board: spared once more
        assert [set(c.bad) for c in fresh] == [{"jaguar_node"}]
        await svc.close()

    asyncio.run(main())


def test_a_device_restored_before_the_robot_was_whole_again_is_not_spared(
        tmp_path: Path) -> None:
    """The same suite run: the board restored the lidar, the robot was all healthy, then the
    lidar hung. What broke after the robot was whole is a new fault: no sparing."""
    async def main() -> None:
        svc, _ = make(tmp_path)
        svc.observations.add(Observation.parse("on(jaguar)", time.monotonic() - 1.0))
        svc.diagnosed(DiagnosisResult((Diagnosis(frozenset(), probability=1.0),), True))
        cands, _ = await svc._diagnose()
        assert [set(c.bad) for c in cands] == [{"jaguar"}, {"jaguar_node"}]
        await svc.close()

    asyncio.run(main())
