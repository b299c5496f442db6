"""A repair that finds only held components says so: it ends ``held``, not ``quarantined``.

The real repair service (dry run) on the TEDUSAR model: a person holds the base for
maintenance and the diagnosis names only the base. Nothing is repaired, and the terminal line
the repair's end makes must not tell the person that the base was quarantined (issue 26: a hold
that ended "repair ended: quarantined ...").
"""

from __future__ import annotations

import asyncio
from pathlib import Path

from host.diagnosis.observations import ObservationSet
from host.events import Event, RepairEnded, describe
from tests.repair.dryrun import plans, result, service_for
from tests.wait import wait_until_async


def test_a_repair_of_only_held_components_ends_held(tmp_path: Path) -> None:
    async def main() -> None:
        events: list[Event] = []
        svc = service_for(tmp_path, ObservationSet(), events, [result("jaguar")],
                          debounce_s=0.0, confirmed=lambda atom: False)
        svc.link(object())  # type: ignore[arg-type]  # a link is up; a dry run sends nothing
        assert svc.hold("jaguar", "maintenance")
        svc.diagnosed(result("jaguar"))
        await wait_until_async(lambda: [e for e in events if isinstance(e, RepairEnded)],
                               60.0, "the repair's end")
        ended = next(e for e in events if isinstance(e, RepairEnded))
        assert ended.outcome == "held", ended
        line = describe(ended)
        assert "quarantined" not in line and "held: jaguar" in line, line
        assert not plans(events)
        await svc.close()

    asyncio.run(main())
