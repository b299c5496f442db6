"""The board client and a board that sends several readings a frame (SUBSCRIBE's ``per_frame``,
MEASUREMENT_BATCH), over ``memory://`` against the firmware's own session on the emulator, on
the loop's simulated clock.

What must hold: the client asks a board with capability ``batch`` for k readings a frame (the
URL's ``per_frame``, else the default of the rate) and never asks one without it; it hands out
every reading as before, numbered without gaps, each stamped with when it was sampled (spaced
as the board's uptimes, not k at one instant); a reconnect asks again; a withheld reading is
still counted as missed; a bad ``per_frame`` in the URL is refused before anything is sent.
"""

from __future__ import annotations

import asyncio
import itertools

import pytest

from host.board import BoardClient
from host.board.link import default_per_frame
from host.board.types import BoardInfo, LinkDown, Reading
from host.transports import open_transport
from host.transports.errors import BadUrl
from protocol.constants import CAP_BATCH
from protocol.messages import Measurement, MeasurementBatch
from tests.host.memboard import CAPS, KEY, MemoryBoard, tedusar
from tests.host.test_client import readings as collect
from tests.host.test_client import reconnected

pytestmark = pytest.mark.looptime

BATCH_CAPS = CAPS | CAP_BATCH


def client(url: str) -> BoardClient:
    loop = asyncio.get_running_loop()
    return BoardClient(url, KEY, clock=loop.time, wall=loop.time)


def spy_on(c: BoardClient) -> list[int]:
    """The type byte of every frame the client's memory transport receives from now on."""
    seen: list[int] = []

    def spy(data: bytes) -> bytes:
        at = data.find(b"\xdb\x58")
        while at >= 0 and at + 3 < len(data):
            seen.append(data[at + 3])
            at = data.find(b"\xdb\x58", at + 2)
        return data

    end = c.transport.end  # type: ignore[attr-defined]
    end.manipulate = spy
    return seen


def test_the_default_holds_a_reading_at_most_30_ms() -> None:
    assert [default_per_frame(r) for r in (1, 10, 33, 34, 50, 67, 100)] == [1, 1, 1, 2, 2, 3, 4]
    assert all(1 <= default_per_frame(r) <= 10 for r in range(0, 256))
    for r in range(1, 101):
        assert (default_per_frame(r) - 1) * 1000 / r <= 30


async def test_a_board_that_can_batch_sends_four_a_frame_stamped_as_sampled() -> None:
    async with MemoryBoard(tedusar(), caps=BATCH_CAPS) as mb, client(mb.url) as c:
        seen = spy_on(c)
        items = await collect(c, 200)
        assert c.per_frame == 4
        got = [x for x in items if isinstance(x, Reading)]
        assert [r.seq for r in got] == list(range(1, len(got) + 1))
        assert sum(r.missed for r in got) == 0
        assert seen.count(MeasurementBatch.TYPE) >= 40 and Measurement.TYPE not in seen
        for a, b in itertools.pairwise(got):
            assert b.host_mono > a.host_mono  # never several readings at one instant
            assert b.host_time > a.host_time
            step = (b.uptime_ms - a.uptime_ms) / 1000
            assert abs((b.host_mono - a.host_mono) - step) < 0.012, (a, b)


async def test_the_url_chooses_and_an_old_board_is_asked_nothing_new() -> None:
    async with MemoryBoard(tedusar(), caps=BATCH_CAPS) as mb, \
            client(mb.url + "?per_frame=10") as c:
        seen = spy_on(c)
        got = [x for x in await collect(c, 50) if isinstance(x, Reading)]
        assert c.per_frame == 10 and seen.count(MeasurementBatch.TYPE) >= 4
        assert [r.seq for r in got] == list(range(1, len(got) + 1))
    async with MemoryBoard(tedusar(), caps=BATCH_CAPS) as mb, \
            client(mb.url + "?per_frame=1") as c:
        seen = spy_on(c)
        await collect(c, 20)
        assert c.per_frame == 1 and MeasurementBatch.TYPE not in seen
    async with MemoryBoard(tedusar()) as mb, client(mb.url + "?per_frame=4") as c:
        seen = spy_on(c)  # a board without the capability: one reading a frame, as ever
        got = [x for x in await collect(c, 20) if isinstance(x, Reading)]
        assert c.per_frame == 1 and MeasurementBatch.TYPE not in seen
        assert seen.count(Measurement.TYPE) >= 20
        assert [r.seq for r in got] == list(range(1, 21))


async def test_a_bad_per_frame_is_refused_before_anything_is_sent() -> None:
    for url in ("memory://b?per_frame=0", "memory://b?per_frame=11", "tcp://h:1?per_frame=x",
                "modbus+tcp://h:1?per_frame=4", "tug://h:1?per_frame=4"):
        with pytest.raises(BadUrl) as err:
            open_transport(url, KEY)
        assert "per_frame" in str(err.value), url


async def test_a_reconnect_asks_again_and_withheld_readings_are_missed() -> None:
    async with MemoryBoard(tedusar(), caps=BATCH_CAPS) as mb, client(mb.url) as c:
        items: list[object] = []
        async for item in c.subscribe(100):
            items.append(item)
            got = [x for x in items if isinstance(x, Reading)]
            if len(got) == 20:
                mb.skip = 3
            if len(got) == 60 and not reconnected(items):
                mb.drop_links()
            if reconnected(items) and len(got) >= 100:
                break
        assert c.per_frame == 4
        assert mb.sessions == 2
        cut = next(i for i, x in enumerate(items) if isinstance(x, LinkDown))
        first = [x for x in items[:cut] if isinstance(x, Reading)]
        assert sum(r.missed for r in first) == 3
        for a, b in itertools.pairwise(first):
            assert b.seq - a.seq - 1 == b.missed
        second = [x for x in items[cut:] if isinstance(x, Reading)]
        assert [r.seq for r in second] == list(range(1, len(second) + 1))  # a new session


def test_stamps_follow_the_uptimes_and_never_go_back() -> None:
    """The stamping rule alone: batches handed to the client together (a host that stalled)
    get stamps that never go backwards; a lying uptime moves a stamp by at most the batch's
    span at the subscribed rate."""
    now = [500.0]
    c = BoardClient("memory://stamps", KEY, clock=lambda: now[0], wall=lambda: now[0] + 1e9)
    c.link.info = BoardInfo("memory://stamps", "memory", 1, "b", "f", 2, BATCH_CAPS, 7, 0, 0,
                       frozenset())
    c.link.subscribed(100, 4)
    sub = c.link.fanout.add()

    def batch(first_seq: int, first_up: int, step: int = 10) -> MeasurementBatch:
        return MeasurementBatch([Measurement(first_seq + i, first_up + step * i, 24000, 0, 0,
                                             [1, 2]) for i in range(4)])

    c.link._dispatch_all([batch(1, 1000)])
    now[0] += 0.1  # the next two batches arrive together, late
    c.link._dispatch_all([batch(5, 1040), batch(9, 1080)])
    now[0] += 0.04
    c.link._dispatch_all([batch(13, 1120, step=100_000)])  # an uptime that lies
    got = [x for x in sub.items if isinstance(x, Reading)]
    assert [r.seq for r in got] == list(range(1, 17))
    monos = [r.host_mono for r in got]
    assert monos[:4] == pytest.approx([499.97, 499.98, 499.99, 500.0])
    assert all(b >= a for a, b in itertools.pairwise(monos))
    assert monos[4] == pytest.approx(500.07) and monos[7] == pytest.approx(500.1)
    assert monos[8:12] == pytest.approx([500.1] * 4)  # would be before the last: held there
    assert monos[12] >= 500.14 - 0.04 - 1e-9  # at most 4 periods back, however it lies
    assert all(r.host_time - r.host_mono == pytest.approx(1e9) for r in got)
    assert c.latest is got[-1]
