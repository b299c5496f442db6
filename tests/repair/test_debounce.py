"""The repair debounce: what it still holds off, and the evidence it no longer waits for.

The real repair service (dry run: plans are made and reported, nothing acts) on the TEDUSAR
model. A diagnosis must hold for ``debounce_s`` before its repair starts — here an hour, so
that a repair that starts at all started without it. A finding its observer confirmed before
saying it (``confirmed``, the observer hub's: a silence in the publisher's own time, a trip the
board's readings bore out) starts the repair at once; a flapping diagnosis, or one that changed
for any other reason while a confirmed finding merely still stands, waits as before.
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

HOUR = 3600.0


def make(tmp: Path, obs: ObservationSet, events: list[Event], firm: set[str],
         diagnosis: list[DiagnosisResult]) -> service.RepairService:
    svc = service_for(tmp, obs, events, diagnosis, debounce_s=HOUR,
                      confirmed=lambda atom: atom in firm)
    svc.link(object())  # type: ignore[arg-type]  # a link is up; a dry run sends nothing
    return svc


def test_a_confirmed_silence_starts_its_repair_without_the_debounce(tmp_path: Path) -> None:
    async def main() -> None:
        obs, events, firm = ObservationSet(), [], {"ok(/scan)"}
        svc = make(tmp_path, obs, events, firm, [result("hokuyo")])
        obs.add(Observation.parse("ok(/scan)", 1.0))
        svc.diagnosed(result())
        obs.add(Observation.parse("~ok(/scan)", 2.0))  # the lidar hung: confirmed silence
        svc.diagnosed(result("hokuyo"))
        await wait_until_async(lambda: plans(events), 60.0, "a repair plan")
        assert "hokuyo" in str(plans(events)[0])
        said = [e.text for e in events if isinstance(e, Note)]
        assert any("~ok(/scan) confirmed by its observer" in t for t in said), said
        await svc.close()

    asyncio.run(main())


def test_a_flapping_diagnosis_is_held_off_while_a_confirmed_finding_stands(
        tmp_path: Path) -> None:
    async def main() -> None:
        obs, events = ObservationSet(), []
        diagnosis = [result("hokuyo")]
        svc = make(tmp_path, obs, events, {"ok(/scan)"}, diagnosis)
        # an unconfirmed finding (a flickering band reading) comes and goes: no repair
        for i in range(21):  # ending on the abnormal reading
            obs.add(Observation.parse("~in_band(jaguar)" if i % 2 == 0 else "in_band(jaguar)",
                                      float(i)))
            svc.diagnosed(result("jaguar") if i % 2 == 0 else result())
            await asyncio.sleep(0)
        assert svc.active and not svc.busy  # waiting out its debounce, not repairing
        # a confirmed silence: repaired at once, and the loop ends (dry run)
        obs.add(Observation.parse("~ok(/scan)", 30.0))
        svc.diagnosed(result("hokuyo"))
        await wait_until_async(lambda: plans(events) and not svc.active, 60.0,
                               "the repair of the confirmed silence to end")
        n = len(plans(events))
        # the silence still stands (confirmed, but not new): the flapping band waits again
        for i in range(21):  # ending on the abnormal reading
            obs.add(Observation.parse("~in_band(jaguar)" if i % 2 == 0 else "in_band(jaguar)",
                                      40.0 + i))
            svc.diagnosed(result("hokuyo", "jaguar") if i % 2 == 0 else result("hokuyo"))
            await asyncio.sleep(0)
        assert not svc.busy and len(plans(events)) == n
        await svc.close()

    asyncio.run(main())


def test_a_silence_whose_observed_input_is_still_ok_waits_for_the_input(tmp_path: Path) -> None:
    """Found with a learned model: hector_mapping's 45 Hz pose, judged silent 12 ms before the
    40 Hz scan it follows (its silence, 4 periods, was the shorter), was repaired at once:
    the mapper restarted for a lidar hang. An output's silence while an input it depends on
    (``/map`` on ``/scan`` here) is observed and still ok is not confirmed evidence: it gets
    the debounce, in which the input's own verdict comes; then it is repaired as before."""
    async def main() -> None:
        obs, events, firm = ObservationSet(), [], {"ok(/map)", "ok(/scan)"}
        svc = make(tmp_path, obs, events, firm, [result("hokuyo")])
        obs.add(Observation.parse("ok(/scan)", 1.0))
        obs.add(Observation.parse("ok(/map)", 1.0))
        svc.diagnosed(result())
        obs.add(Observation.parse("~ok(/map)", 2.0))  # judged first, /scan still ok
        svc.diagnosed(result("hector_mapping"))
        assert svc.active and not svc.busy  # waiting out the (hour's) debounce
        said = [e.text for e in events if isinstance(e, Note)]
        assert not any("confirmed by its observer" in t for t in said), said
        obs.add(Observation.parse("~ok(/scan)", 2.012))  # the lidar's silence, judged now
        svc.diagnosed(result("hokuyo"))
        await wait_until_async(lambda: plans(events), 60.0, "a repair plan")
        assert "hokuyo" in str(plans(events)[0]) and "hector" not in str(plans(events)[0])
        await svc.close()

    asyncio.run(main())
