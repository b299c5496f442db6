"""Lying frames on a real link: the emulated board's firmware session, the board client and the
hardware observer, on the loop's simulated clock.

A frame with a valid checksum but contradictory content — a trip EVENT for a healthy channel, a
MEASUREMENT whose on/off mask says a powered device is off — is written into the link between
the board's real pushes. Nothing the observer says changes. A real short on the same channel is
still seen as a trip within a few readings of the board's own trip.
"""

from __future__ import annotations

import asyncio

import pytest

from host.board import BoardClient
from host.observers import Device, HardwareObserver, Update
from protocol.constants import EV_TRIP, F_SHORT, ST_ON, ST_TRIPPED
from protocol.framing import encode_frame
from protocol.messages import Event, Measurement
from tests.host.memboard import KEY, MemoryBoard, tedusar

pytestmark = pytest.mark.looptime

HOKUYO = Device("hokuyo", 3, (0.2, 1.2))


async def until(what: object, within: float = 10.0) -> None:
    loop = asyncio.get_running_loop()
    end = loop.time() + within
    while not what():  # type: ignore[operator]
        assert loop.time() < end, f"not within {within} s"
        await asyncio.sleep(0.005)


async def test_lying_frames_change_nothing_and_a_real_short_still_trips() -> None:
    loop = asyncio.get_running_loop()
    async with MemoryBoard(tedusar()) as mb:
        c = BoardClient(mb.url, KEY, clock=loop.time)
        await c.connect()
        await c.switch("hokuyo", True)
        h = HardwareObserver({"hokuyo": HOKUYO})
        seen: list[tuple[float, Update]] = []

        async def observe() -> None:
            h.feed(await c.state(), loop.time())
            async for item in c.subscribe(100):
                seen.extend((loop.time(), u) for u in h.feed(item, loop.time()))

        task = asyncio.ensure_future(observe())
        healthy = {"link(board)": True, "on(hokuyo)": True, "in_band(hokuyo)": True,
                   "tripped(hokuyo)": False}
        await until(lambda: h.asserted == healthy)
        mark = len(seen)
        board_end = mb.links[-1]
        last = c.latest
        assert last is not None
        trip = Event(9999, last.uptime_ms, EV_TRIP, 3, ST_ON, ST_TRIPPED, F_SHORT, 9000, 0)
        board_end.write(encode_frame(Event.TYPE, 0, trip.payload()))
        await asyncio.sleep(0.5)
        last = c.latest
        assert last is not None
        off = Measurement(last.seq + 1, last.uptime_ms + 10, last.input_mv,
                          last.on_mask & ~(1 << 3), last.fault_mask | 1 << 3,
                          [0 if i == 3 else ma for i, ma in enumerate(last.currents_ma)])
        board_end.write(encode_frame(Measurement.TYPE, 0, off.payload()))
        await asyncio.sleep(1.0)  # a hundred real readings later, on the simulated clock
        assert seen[mark:] == [] and h.asserted == healthy
        # a real short on the same channel: the board trips it, and the readings confirm it
        mb.emu.inject("hokuyo", "short", {})
        t0 = loop.time()
        await until(lambda: h.asserted.get("tripped(hokuyo)") is True)
        tripped_at = next(t for t, u in seen[mark:] if str(getattr(u, "literal", "")) ==
                          "tripped(hokuyo)")
        assert tripped_at - t0 < 0.1  # the board's trip samples, then three readings
        assert h.asserted["on(hokuyo)"] is False
        task.cancel()
        await asyncio.wait([task])
        await c.close()
