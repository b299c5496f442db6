"""A hang found in the publisher's own time is repaired without the debounce (the real daemon).

``dxboard run --emulate`` (a subprocess, ``tests.daemon.runner``): once the robot is healthy the
lidar hangs; /scan's silence is confirmed in its publisher's own time, so the repair service
starts the repair without the 0.5 s debounce and says so in the journal, before the repair's
first action; the robot is healthy again. The debounce itself (a flapping diagnosis still
held off) is proved on the service in ``tests/repair/test_debounce.py``.
"""

from __future__ import annotations

from collections.abc import Iterator

import pytest

from host.journal import ActionRecord, Note
from tests.daemon.runner import RunningDaemon, healthy, healthy_robot

HEAL_S = 120.0


@pytest.fixture(scope="module")
def robot(tmp_path_factory: pytest.TempPathFactory) -> Iterator[RunningDaemon]:
    with healthy_robot(tmp_path_factory.mktemp("confirmed"), HEAL_S) as d:
        yield d


def test_a_confirmed_silence_is_repaired_without_the_debounce(robot: RunningDaemon) -> None:
    d = robot
    d.wait_for(healthy, HEAL_S, "healthy")
    d.caught_up()
    mark = max(e.id for e in d.journal())
    d.inject("hokuyo", "hang")
    d.wait_for(lambda s: any(r["action"] == "power_cycle" for r in s["repairs"])
               and healthy(s), HEAL_S, "the lidar power-cycled and the robot healthy again")
    d.caught_up()
    after = [e for e in d.journal() if e.id > mark]
    said = [e for e in after if isinstance(e.payload, Note)
            and "~ok(/scan) confirmed by its observer" in e.payload.text]
    acts = [e for e in after if isinstance(e.payload, ActionRecord)]
    assert said, [e.payload for e in after if isinstance(e.payload, Note)]
    assert acts and said[0].id < acts[0].id  # said as the repair was decided, before it acted
