"""A repair held off while the board link was down starts once the link is back.

Found in the suite: a brown-out reboot brought the board back with every device off; the
diagnosis naming them was confirmed (so its repair was due at once) a moment before the new
boot's state set the link up, the repair was refused ("no repair while the board link is
down"), and with the diagnosis unchanged after that nothing started it again: the robot stayed
down for the test's 90 s. The real repair service (dry run: plans are made, nothing acts) on
the TEDUSAR model.
"""

from __future__ import annotations

import asyncio
from pathlib import Path

from host.diagnosis.observations import Observation, ObservationSet
from host.diagnosis.result import DiagnosisResult
from host.events import Event, Note
from host.repair import service
from tests.repair.dryrun import plans, result, service_for
from tests.wait import wait_until_async

DEBOUNCE_S = 0.2


def make(tmp: Path, obs: ObservationSet, events: list[Event],
         diagnosis: list[DiagnosisResult]) -> service.RepairService:
    return service_for(tmp, obs, events, diagnosis, debounce_s=DEBOUNCE_S,
                       confirmed=lambda atom: atom == "ok(/map)")


def test_a_repair_refused_while_the_link_was_down_starts_when_it_is_back(tmp_path: Path
                                                                         ) -> None:
    async def main() -> None:
        obs, events = ObservationSet(), []
        down = result("hokuyo", "jaguar")
        svc = make(tmp_path, obs, events, [down])
        svc.link(object())  # type: ignore[arg-type]  # up; a dry run sends nothing
        obs.add(Observation.parse("ok(/map)", 1.0))
        svc.diagnosed(result())
        svc.link(None)  # the board rebooted
        obs.add(Observation.parse("~ok(/map)", 2.0))  # confirmed: due at once
        svc.diagnosed(down)
        await wait_until_async(
            lambda: any(isinstance(e, Note) and "link is down" in e.text for e in events),
            60.0, "the repair refused while the link is down")
        assert plans(events) == [] and not svc.active
        svc.link(object())  # type: ignore[arg-type]  # the new boot's state: up again
        await wait_until_async(lambda: plans(events), 60.0, "the repair once the link is up")
        assert {"hokuyo", "jaguar"} <= {a for s in plans(events)[0].steps for a in s.args}
        await svc.close()

    asyncio.run(main())


def test_the_link_back_starts_nothing_on_a_healthy_robot_or_beside_a_pending_repair(
        tmp_path: Path) -> None:
    async def main() -> None:
        obs, events = ObservationSet(), []
        diagnosis = [result()]
        svc = make(tmp_path, obs, events, diagnosis)
        svc.link(object())  # type: ignore[arg-type]
        svc.diagnosed(result())
        svc.link(None)
        svc.link(object())  # type: ignore[arg-type]
        assert not svc.active  # healthy: nothing to repair
        svc.link(None)
        diagnosis[0] = result("hokuyo")
        svc.diagnosed(result("hokuyo"))  # not confirmed: waits out its debounce
        pending = svc._pending
        svc.link(object())  # type: ignore[arg-type]
        assert svc._pending is pending  # the debounce already under way goes on, not twice
        await wait_until_async(lambda: plans(events), 60.0, "the one repair")
        await wait_until_async(lambda: not svc.active, 60.0, "the repair to end")
        assert len(plans(events)) == 1
        await svc.close()

    asyncio.run(main())
