"""Unknown is not healthy: a component whose observations expired is unknown, never "healthy".

Issue 25 item 6: an overloaded daemon's last word was "all healthy", made from observations that
had just expired. The real ``DiagnosisRunner`` (the daemon's) over the TEDUSAR model: every
observable atom observed healthy, then the topics expire; the record it emits must name what
became unknown, and the line a person reads must not say "all healthy".
"""

from __future__ import annotations

from host.diagnosis import Diagnoser, generate, load_system
from host.diagnosis.coverage import Coverage
from host.diagnosis.healthy import healthy_values
from host.diagnosis.observations import Observation, ObservationSet
from host.diagnosis.runner import DiagnosisRunner
from host.events import DiagnosisRecord, Event, describe, event_from_json
from tests.diagnosis.conftest import TEDUSAR


def _records(events: list[Event]) -> list[DiagnosisRecord]:
    return [e for e in events if isinstance(e, DiagnosisRecord)]


async def test_expired_observations_make_their_components_unknown_not_healthy() -> None:
    theory = generate(load_system(TEDUSAR))
    now = [0.0]
    observations = ObservationSet()
    events: list[Event] = []
    runner = DiagnosisRunner(Diagnoser(theory), observations, events.append,
                             clock=lambda: now[0])
    try:
        healthy = healthy_values(theory)
        for atom, value in healthy.items():  # topics valid 3 s, the rest for good
            lit = f"{'' if value else '~'}{atom}"
            observations.add(Observation.parse(lit, 0.0, "test",
                                               3.0 if atom.startswith("ok(") else None))
        await runner.run("observation")
        first = _records(events)[-1]
        assert first.diagnoses == ((),) and first.unknown == ()
        assert "all healthy" in describe(first)

        now[0] = 10.0  # the topics expired: the daemon fell behind, nothing new came
        await runner.run("safety tick")
        last = _records(events)[-1]
        assert last is not first
        assert {"hokuyo_node", "hector_mapping", "jaguar_node", "imu"} <= set(last.unknown)
        assert "rviz" not in last.unknown  # its running(rviz) is still known
        line = describe(last)
        assert "all healthy" not in line and "unknown" in line and "hokuyo_node" in line
        assert event_from_json("diagnosis", last.to_json()) == last  # the journal keeps it

        for atom in ("ok(/scan)", "ok(/map)", "ok(/slam_out_pose)"):  # /scan is back
            observations.add(Observation.parse(atom, 10.0, "test", 3.0))
        await runner.run("observation")
        back = _records(events)[-1]
        assert "hokuyo_node" not in back.unknown and "jaguar_node" in back.unknown
    finally:
        runner.close()


def test_atoms_nobody_observed_do_not_make_anything_unknown() -> None:
    coverage = Coverage(generate(load_system(TEDUSAR)))
    assert coverage.unknown(set(), set()) == ()
    assert coverage.unknown({"ok(/scan)"}, {"ok(/scan)"}) == ()
    assert set(coverage.unknown({"ok(/scan)"}, set())) == {"hokuyo", "hokuyo_node",
                                                            "hector_mapping"}


