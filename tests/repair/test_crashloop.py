"""A driver that exits at once after every start because its device is off or absent is
diagnosed as the device, not restarted until it is quarantined (issue 28, item 1).

The real repair service of the tedusar robot (``tests/repair/test_settle_wait.py``'s harness,
in-process, dry run), its observations set by the test: the node's ``running`` turned true and
false again within its settle time, twice. Before, the service planned the node's restart every
time (and the attempt limiter quarantined the node after three): with the device held by a
person (its channel switched off on the board), the held device was left out and the driver
alone restarted; with a device the board cannot switch (the USB IMU), the driver alone was the
diagnosis. A driver that died while its device is quarantined and off is not restarted
either, before any loop: it would spend its own attempts on its device's fault.
"""

from __future__ import annotations

import asyncio
import time
from pathlib import Path

from host.diagnosis.model import load_system
from host.diagnosis.observations import Observation, ObservationSet
from host.diagnosis.result import Diagnosis, DiagnosisResult
from host.events import Event, Note
from host.repair import service
from host.repair.planner import RepairPlanner
from host.repair.processes import load_processes
from tests.repair.test_shed import TEDUSAR, Board, board


def make(tmp_path: Path, *bad: frozenset[str]) -> tuple[service.RepairService, list[Event]]:
    model = load_system(TEDUSAR / "system.yaml")
    events: list[Event] = []

    async def diagnose() -> DiagnosisResult:
        return DiagnosisResult(tuple(Diagnosis(b, probability=1.0 / len(bad)) for b in bad), True)

    svc = service.build(
        RepairPlanner.for_system(TEDUSAR), model,
        load_processes(TEDUSAR / "system.yaml", model), observations=ObservationSet(),
        observable=set(), diagnose=diagnose, emit=events.append, logs_dir=tmp_path, env={},
        device_boot_s={"hokuyo": 0.3}, dry_run=True)
    svc.link(Board(board(set())))  # type: ignore[arg-type]
    return svc, events


def crash(obs: ObservationSet, node: str, at: float, runs: int, run_s: float = 0.4) -> float:
    """``node`` started and died ``runs`` times, each run ``run_s`` long; the time after."""
    for _ in range(runs):
        obs.add(Observation.parse(f"running({node})", at))
        obs.add(Observation.parse(f"-running({node})", at + run_s))
        at += run_s + 1.0
    return at


def steps_on(rnd: object, component: str) -> list[str]:
    choice = getattr(rnd, "choice", None)
    if choice is None:
        return []
    return [f"{s.action}({', '.join(s.args)})" for s in choice.plan.steps
            if component in s.args]


def test_a_driver_that_dies_at_once_while_its_device_is_held_off_is_not_restarted(
        tmp_path: Path) -> None:
    async def main() -> None:
        svc, events = make(tmp_path, frozenset({"hokuyo", "hokuyo_node"}))
        now = time.monotonic() - 30.0
        svc.observations.add(Observation.parse("-on(hokuyo)", now))
        svc.board_switched(3, False)  # a person switched the lidar's channel off
        assert "hokuyo" in svc.executor.held
        crash(svc.observations, "hokuyo_node", now, 2)
        rnd = await svc.loop.repair_once()
        assert steps_on(rnd, "hokuyo_node") == [], rnd  # not restarted: it waits for hokuyo
        assert any(isinstance(e, Note) and "hokuyo_node" in e.text and "hokuyo" in e.text
                   and "not restarted" in e.text for e in events), events
        await svc.close()

    asyncio.run(main())


def test_a_driver_that_dies_at_once_blames_its_unobserved_device(tmp_path: Path) -> None:
    async def main() -> None:
        svc, events = make(tmp_path, frozenset({"imu_node"}))
        crash(svc.observations, "imu_node", time.monotonic() - 30.0, 2)
        cands, _ = await svc._diagnose()
        # the IMU (USB, not on the board: nothing observes it) is the suspect; it cannot be
        # repaired here, so its driver is not restarted until it is back
        assert [set(c.bad) for c in cands] == [{"imu"}]
        rnd = await svc.loop.repair_once()
        assert steps_on(rnd, "imu_node") == [], rnd
        assert any(isinstance(e, Note) and e.text.startswith("imu_node: exits at once")
                   for e in events), events
        await svc.close()

    asyncio.run(main())


def test_a_driver_that_dies_at_once_with_its_device_unknown_power_cycles_it(
        tmp_path: Path) -> None:
    async def main() -> None:
        svc, _ = make(tmp_path, frozenset({"hokuyo_node"}))
        crash(svc.observations, "hokuyo_node", time.monotonic() - 30.0, 2)
        cands, _ = await svc._diagnose()  # the lidar's current is unknown (no band reading)
        assert [set(c.bad) for c in cands] == [{"hokuyo", "hokuyo_node"}]
        rnd = await svc.loop.repair_once()
        assert steps_on(rnd, "hokuyo"), rnd  # the device is repaired, then its driver
        assert steps_on(rnd, "hokuyo_node")
        await svc.close()

    asyncio.run(main())


def test_a_driver_that_ran_or_whose_device_is_well_is_restarted_as_before(
        tmp_path: Path) -> None:
    async def main() -> None:
        svc, _ = make(tmp_path, frozenset({"hokuyo_node"}))
        now = time.monotonic() - 60.0
        crash(svc.observations, "hokuyo_node", now, 2, run_s=30.0)  # ran, then crashed
        cands, _ = await svc._diagnose()
        assert [set(c.bad) for c in cands] == [{"hokuyo_node"}]
        # dies at once, but its device is on and draws its current: the node's own fault
        svc2, _ = make(tmp_path, frozenset({"hokuyo_node"}))
        svc2.observations.add(Observation.parse("on(hokuyo)", now))
        svc2.observations.add(Observation.parse("in_band(hokuyo)", now))
        crash(svc2.observations, "hokuyo_node", now, 2)
        cands, _ = await svc2._diagnose()
        assert [set(c.bad) for c in cands] == [{"hokuyo_node"}]
        rnd = await svc2.loop.repair_once()
        assert steps_on(rnd, "hokuyo_node")
        await svc.close()
        await svc2.close()

    asyncio.run(main())


def test_a_dead_driver_of_a_quarantined_device_is_not_restarted_before_any_loop(
        tmp_path: Path) -> None:
    async def main() -> None:
        svc, events = make(tmp_path, frozenset({"hokuyo", "hokuyo_node"}))
        now = time.monotonic() - 30.0
        await svc.quarantine("hokuyo", "its switch is stuck off")  # its repairs failed
        svc.observations.add(Observation.parse("-on(hokuyo)", now))
        svc.observations.add(Observation.parse("running(hokuyo_node)", now - 100.0))
        svc.observations.add(Observation.parse("-running(hokuyo_node)", now))  # it ran, died
        assert svc.crashloops.looping("hokuyo_node") is None
        cands, _ = await svc._diagnose()
        assert [set(c.bad) for c in cands] == [{"hokuyo"}]  # it waits for its device
        rnd = await svc.loop.repair_once()
        assert steps_on(rnd, "hokuyo_node") == [], rnd
        assert any(isinstance(e, Note) and e.text.startswith("hokuyo_node: its device hokuyo "
                                                             "is quarantined") for e in events)
        # cleared by a person: the device is repaired and its driver restarted
        await svc.clear("hokuyo")
        cands, _ = await svc._diagnose()
        assert [set(c.bad) for c in cands] == [{"hokuyo", "hokuyo_node"}]
        await svc.close()

    asyncio.run(main())


def test_one_early_death_is_no_loop() -> None:
    from host.repair.crashloop import CrashLoops

    obs = ObservationSet()
    loops = CrashLoops(obs, {"n": 2.0}, ["n"])
    at = crash(obs, "n", 0.0, 1)
    assert loops.looping("n") is None
    at = crash(obs, "n", at, 1)
    assert loops.looping("n") is not None
    assert loops.looping("n", at + 200) is not None
    assert loops.looping("n", at + 400) is None  # so long ago: it is tried once more
    obs.add(Observation.parse("running(n)", at + 10))
    assert loops.looping("n") is None  # it runs now
    obs.add(Observation.parse("-running(n)", at + 100))  # this run held: no loop any more
    assert loops.looping("n") is None


def test_on_a_busy_machine_a_run_is_short_within_the_stretched_settle_time() -> None:
    """A driver's start takes ``k`` times longer on a machine busy ``k`` times over (the
    executor gives its steps that much more time): 7 s runs at k = 3 are a loop, at k = 1 not."""
    from host.repair.crashloop import CrashLoops

    for k, loops_then in ((1.0, False), (3.0, True)):
        obs = ObservationSet()
        loops = CrashLoops(obs, {"n": 2.0}, ["n"], stretch=lambda k=k: k)
        crash(obs, "n", 0.0, 2, run_s=7.0)
        assert (loops.looping("n") is not None) is loops_then, k


def test_runs_this_host_ended_are_no_crashes() -> None:
    from host.repair.crashloop import CrashLoops

    obs = ObservationSet()
    stops: dict[str, float] = {}
    loops = CrashLoops(obs, {"n": 2.0}, ["n"], stops)
    at = 0.0
    for _ in range(3):  # a restart's stop_node ends each run
        stops["n"] = at + 0.2
        at = crash(obs, "n", at, 1)
    assert loops.looping("n") is None
    at = crash(obs, "n", at, 2)  # then it dies by itself
    assert loops.looping("n") is not None
