"""The hub's timers on the loop's simulated clock: a receding deadline keeps its timer.

A board's link deadline moves on with each of its readings (a hundred a second). The hub keeps
the timer it has and moves it on when it fires, rather than replacing it with every reading;
the observer is still ticked exactly when its deadline is due, never before: a board that
falls silent is judged lost at its deadline, confirmed by an on-time tick.
"""

from __future__ import annotations

import asyncio

import pytest

from host.board.types import Reading
from host.observers import (
    Device,
    FrequencyObserver,
    HardwareObserver,
    ObserverHub,
    TopicMessage,
    Update,
)
from host.observers.payload import encode
from host.observers.silence import JITTER_S

pytestmark = pytest.mark.looptime

HOKUYO = Device("hokuyo", 3, (0.2, 1.2))


class Counting(HardwareObserver):
    """Records when it was ticked."""

    def __init__(self) -> None:
        super().__init__({"hokuyo": HOKUYO}, link_timeout=0.25, settle=3)
        self.ticks: list[float] = []

    def tick(self, now: float) -> list[Update]:
        self.ticks.append(now)
        return super().tick(now)


async def test_a_receding_link_deadline_ticks_only_when_due() -> None:
    loop = asyncio.get_running_loop()
    h = Counting()
    said: list[Update] = []
    hub = ObserverHub([h], said.extend, clock=loop.time)
    await hub.start()
    handles = 0
    call_later = loop.call_later

    def counted(*args: object, **kw: object) -> asyncio.TimerHandle:
        nonlocal handles
        handles += getattr(args[1], "__name__", "") == "_fire"  # the hub's, not the sleeps'
        return call_later(*args, **kw)  # type: ignore[arg-type]

    loop.call_later = counted  # type: ignore[method-assign]
    try:
        t0 = loop.time()
        for seq in range(1, 201):  # two seconds of readings at 100 Hz
            currents = (0, 0, 0, 500, 0, 0, 0, 0, 0, 0)
            hub.feed_board(Reading(0.0, loop.time(), 1, seq, seq * 10, 12000, 1 << 3, 0,
                                   currents))
            await asyncio.sleep(0.01)
        last = loop.time() - 0.01
        while h.asserted.get("link(board)") is not False:
            assert loop.time() < last + 5.0
            await asyncio.sleep(0.001)
    finally:
        loop.call_later = call_later  # type: ignore[method-assign]
    lost = next(u.time for u in said if str(getattr(u, "literal", "")) == "~link(board)")
    assert lost == pytest.approx(last + 0.25 + JITTER_S, abs=0.003)
    # ticks only when something was due: the refreshes (every second) and the silence
    # (noticed, then confirmed) — not one per reading
    assert all(t >= t0 for t in h.ticks) and len(h.ticks) <= 8
    assert handles <= 20  # a timer per second or so, not one per reading (200)
    await hub.close()


async def test_every_topic_message_is_the_way_in_of_every_frequency_observer() -> None:
    loop = asyncio.get_running_loop()
    scan = FrequencyObserver("/scan", rate=40, tolerance=10, window=0.5)
    imu = FrequencyObserver("/imu_data", rate=100, tolerance=25, window=0.5)
    hub = ObserverHub([scan, imu], lambda _: None, clock=loop.time)
    assert scan.way_in is hub.way_in and imu.way_in is hub.way_in
    hub.feed_message(TopicMessage(loop.time() + 0.5, "/imu_data", encode({"stamp": 0.5})))
    assert scan.way_in is not None and scan.way_in.last == pytest.approx(loop.time() + 0.5)
    await hub.close()


async def test_one_observed_topic_has_no_way_in_to_excuse_its_silence() -> None:
    """With one topic observed, "nothing came in on any topic" is that topic's own silence: a
    hang of its only publisher must not wait for the starvation cap."""
    loop = asyncio.get_running_loop()
    scan = FrequencyObserver("/scan", rate=40, tolerance=10, window=0.5)
    hub = ObserverHub([scan], lambda _: None, clock=loop.time)
    assert scan.way_in is None
    await hub.close()
