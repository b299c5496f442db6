"""A daemon that falls behind says so (issue 25): ``host.daemon.lagwatch`` turns the metrics'
loop-lag probe into ``LoopLag`` events, and ``/diagnostics`` (``dxboard/daemon``: WARN with the
lag in its values) and the page's headline say it.

The probe and the watch run on a real event loop that is held up for 1.5 s (as a daemon on an
overloaded machine is); the folds are fed the event they would get from the daemon's stream.
"""

from __future__ import annotations

import asyncio
import time

from host.daemon import lagwatch
from host.events import LoopLag, Stamped
from host.fleet.metrics import LagProbe
from host.fold import EventFold
from host.ros.status import OK, WARN, Diagnostics
from host.web.headline import headline
from host.web.status import Status

DEADLINE_S = 60.0  # generous: only a broken watch takes this long


def test_judge_says_falling_behind_catching_up_and_big_changes_only() -> None:
    first = lagwatch.judge(0.01, None, 0.0, 0.0)
    assert first == LoopLag(0.01, False, 1.0)
    assert lagwatch.judge(0.2, first, 1.0, 0.0) is None  # on time: nothing new
    behind = lagwatch.judge(2.0, first, 1.0, 0.0)
    assert behind == LoopLag(2.0, True, 1.0)
    assert lagwatch.judge(2.2, behind, 5.0, 1.0) is None  # a small change
    assert lagwatch.judge(3.0, behind, 2.0, 1.0) is None  # too soon after the last
    assert lagwatch.judge(3.0, behind, 5.0, 1.0) == LoopLag(3.0, True, 1.0)
    assert lagwatch.judge(0.1, behind, 5.5, 5.0) == LoopLag(0.1, False, 1.0)


def test_a_stalled_loop_is_told_behind_then_caught_up() -> None:
    async def main() -> list[LoopLag]:
        said: list[LoopLag] = []
        probe = LagProbe()
        tasks = [asyncio.ensure_future(probe.run()),
                 asyncio.ensure_future(lagwatch.watch(probe, said.append))]  # type: ignore[arg-type]
        try:
            await asyncio.sleep(1.2)  # a few wakes on time
            time.sleep(1.5)  # the loop held up, as by an overloaded machine
            end = time.monotonic() + DEADLINE_S
            while not (said and said[-1].behind is False and any(e.behind for e in said)):
                assert time.monotonic() < end, f"behind, then caught up: {said}"
                await asyncio.sleep(0.1)
        finally:
            for t in tasks:
                t.cancel()
            await asyncio.gather(*tasks, return_exceptions=True)
        return said

    said = asyncio.run(main())
    assert said[0].behind is False  # on time before the stall
    behind = next(e for e in said if e.behind)
    assert behind.lag_s > behind.limit_s


def test_diagnostics_warn_with_the_lag() -> None:
    fold = EventFold()
    view = Diagnostics(["hokuyo"], fold)
    daemon = view.statuses()[-1]
    assert (daemon.name, daemon.level) == ("dxboard/daemon", OK)
    assert fold.feed(Stamped(0.0, 0.0, LoopLag(2.345, True, 1.0)))
    daemon = view.statuses()[-1]
    assert daemon.level == WARN
    assert "behind: its event loop runs 2.3 s late" in daemon.message
    assert ("loop_lag_s", "2.345") in daemon.values and ("behind", "true") in daemon.values
    fold.feed(Stamped(0.0, 0.0, LoopLag(0.02, False, 1.0)))
    daemon = view.statuses()[-1]
    assert daemon.level == OK and ("behind", "false") in daemon.values


def test_the_headline_says_behind() -> None:
    now = time.time()
    st = Status(board_link_up=True, updated=now, diagnosed_at=now, loop_lag_s=2.3,
                loop_behind=True)
    h = headline(st, now, 30.0)
    assert h["state"] == "behind" and "2.3 s late" in h["text"]
    st = Status(board_link_up=True, updated=now, diagnosed_at=now, loop_lag_s=0.1)
    assert headline(st, now, 30.0)["state"] == "healthy"
