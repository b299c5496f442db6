"""The TCP front end's limits, in-process: read timeout, connection limit, slow readers."""

from __future__ import annotations

import asyncio
import contextlib
import itertools
import json
from collections.abc import Iterator

import pytest

from emulator import model
from emulator.control import Background
from emulator.frontends import FrontEnds
from emulator.sim import Emulator
from protocol.connection import HOST, Connection
from protocol.messages import (
    Ack,
    AuthPing,
    GetState,
    Measurement,
    MeasurementBatch,
    Ping,
    Pong,
    State,
    Subscribe,
)
from tests.emulator.conftest import TEDUSAR
from tests.emulator.wire import KEY, Wire
from tests.rates import assert_no_gaps
from tests.wait import wait_until_async


@pytest.fixture(params=[600])
def served(request: pytest.FixtureRequest) -> Iterator[tuple[Background, FrontEnds,
                                                             tuple[str, int]]]:
    """The board's front ends with a read timeout of ``param`` ms and at most 6 clients."""
    cfg = json.loads((TEDUSAR / "board.json").read_text())
    cfg["board"]["key"] = KEY.hex()
    emu = Emulator(model.load(TEDUSAR), board_config=cfg)
    fronts = FrontEnds(emu, read_timeout_ms=request.param, max_clients=6)
    with Background(emu) as bg:
        urls = bg.run(fronts.start())
        host, port = urls["board"].split("://")[1].rsplit(":", 1)
        yield bg, fronts, (host, int(port))
        bg.run(fronts.stop())


async def _closed_within(reader: asyncio.StreamReader, seconds: float) -> bool:
    loop = asyncio.get_running_loop()
    end = loop.time() + seconds
    try:
        while loop.time() < end:
            if not await asyncio.wait_for(reader.read(65536), end - loop.time()):
                return True
    except (TimeoutError, ConnectionResetError):
        pass
    return False


async def test_idle_strangers_closed_the_pinging_host_kept(
        served: tuple[Background, FrontEnds, tuple[str, int]]) -> None:
    _, _, address = served
    silent = await Wire.open(address)
    stranger = await Wire.open(address)  # PINGs without proving the key
    host = await Wire.open(address)
    assert isinstance(await host.request(AuthPing(1)), Pong)

    async def ping() -> None:  # every 0.2 s at most, a third of the read timeout
        assert isinstance(await host.request(Ping(1)), Pong)
        with contextlib.suppress(AssertionError, ConnectionError, TimeoutError):
            await stranger.request(Ping(2), timeout=0.2)

    await wait_until_async(lambda: _closed_within(silent.reader, 0.2), each=ping,
                           what="the silent connection closed", interval=0)
    await wait_until_async(lambda: _closed_within(stranger.reader, 0.2), each=ping,
                           what="the stranger closed though it PINGs", interval=0)
    assert isinstance(await host.request(GetState()), State)
    await host.close()


# a read timeout longer than the test: the host sits silent while twenty clients come and go,
# which on a busy machine took longer than 600 ms, and the host was closed for its silence (the
# read timeout, tested above), not evicted
@pytest.mark.parametrize("served", [60_000], indirect=True)
async def test_strangers_never_lock_the_host_out(
        served: tuple[Background, FrontEnds, tuple[str, int]]) -> None:
    """Six slots, two of them for the host only: strangers that only PING are evicted for
    a newcomer (the idlest first), the authenticated host is never evicted, and a newcomer is
    refused only when every slot is the host's."""
    _, _, address = served
    host = await Wire.open(address)
    assert isinstance(await host.request(AuthPing(1)), Pong)
    strangers = [await Wire.open(address) for _ in range(8)]
    for w in strangers[-4:]:
        assert isinstance(await w.request(Ping(3)), Pong)
    for w in strangers[:4]:  # the first four were evicted for the last four
        assert await _closed_within(w.reader, 2.0)
    for attempt in range(12):  # a fresh client is always served
        fresh = await Wire.open(address)
        assert isinstance(await fresh.request(GetState()), State), attempt
        await fresh.close()
    assert isinstance(await host.request(GetState()), State)  # never evicted
    hosts = [host]
    for _ in range(5):
        w = await Wire.open(address)
        assert isinstance(await w.request(AuthPing(2)), Pong)
        hosts.append(w)
    r, w = await asyncio.open_connection(*address)  # six host sessions: no room at all
    assert await _closed_within(r, 2.0)
    w.close()
    for x in hosts:
        assert isinstance(await x.request(Ping(4)), Pong)
        await x.close()


@pytest.mark.parametrize("served", [30000], indirect=True)
async def test_a_client_that_never_reads_does_not_hold_up_others(
        served: tuple[Background, FrontEnds, tuple[str, int]]) -> None:
    _, _, address = served
    slow = await Wire.open(address)
    fast = await Wire.open(address)
    for c in (slow, fast):
        assert isinstance(await c.request(Subscribe(100)), Ack)
    seqs: list[int] = []
    while len(seqs) < 200:  # the slow one never reads; the fast one drains everything
        m = await fast.next(lambda e: isinstance(e, Measurement))
        assert isinstance(m, Measurement)
        seqs.append(m.seq)
    assert_no_gaps(seqs, "the fast client's measurements")
    await slow.close()
    await fast.close()


class _Blocked:
    """A writer whose peer does not read: ``drain`` waits until ``release``."""

    def __init__(self) -> None:
        self.data = bytearray()
        self.go = asyncio.Event()

    def write(self, data: bytes) -> None:
        self.data += data

    async def drain(self) -> None:
        await self.go.wait()

    def close(self) -> None:
        pass

    async def wait_closed(self) -> None:
        pass


def _seqs(conn: Connection, data: bytes, sizes: list[int] | None = None) -> list[int]:
    """The seq of every reading in ``data`` (MEASUREMENT or MEASUREMENT_BATCH); ``sizes``
    gets the number of readings in each frame."""
    out = []
    for i in range(0, len(data), 1024):
        conn.receive_data(data[i:i + 1024])
        for m in conn.events():
            got = m.readings if isinstance(m, MeasurementBatch) else [m] if isinstance(
                m, Measurement) else []
            out.extend(r.seq for r in got)
            if got and sizes is not None:
                sizes.append(len(got))
    return out


@pytest.mark.parametrize("per_frame", [1, 4])
async def test_net_skips_measurements_for_a_stuck_writer_only(per_frame: int) -> None:
    """Net over in-memory streams, on the test HAL's simulated clock; with ``per_frame`` 4
    the free writer gets its readings four a frame, none lost, and the stuck one's gap shows
    in its batches as well."""
    from benchmarks._rigs.testhal import Rig
    from firmware.net import HARD_CAP, Net

    rig = Rig(board={"key": KEY.hex()})
    net = Net(rig.app, "test", 0)
    stuck, free = _Blocked(), _Blocked()
    free.go.set()
    conns = []
    tasks = []
    for w in (stuck, free):
        reader = asyncio.StreamReader()
        conn = Connection(HOST, KEY)
        tasks.append(asyncio.create_task(net.serve_stream(reader, w)))
        await asyncio.sleep(0)
        reader.feed_data(conn.send(Subscribe(100, per_frame, req_id=1)))
        conns.append(conn)
    for _ in range(1000):  # 10 simulated seconds
        rig.run(10)
        net.pump(rig.hal.now)
        await asyncio.sleep(0)
    stuck_client = next(c for c in net.clients if c.writer is stuck)
    assert stuck_client.skipped > 900
    assert stuck_client.n <= HARD_CAP and not stuck_client.closed
    sizes: list[int] = []
    seqs = _seqs(conns[1], bytes(free.data), sizes)
    assert seqs == list(range(1, 1001))
    assert sizes == [per_frame] * (1000 // per_frame)
    stuck.go.set()  # the peer reads at last: what it gets shows the gap
    for _ in range(8):
        rig.run(10)
        net.pump(rig.hal.now)
        await asyncio.sleep(0)
    got = _seqs(conns[0], bytes(stuck.data))
    assert got[0] < 100 and got[-1] > 1000
    assert any(b - a > 1 for a, b in itertools.pairwise(got))
    for t in tasks:
        t.cancel()


def test_the_emulator_offers_batched_readings() -> None:
    """The emulated board's HELLO has capability batch (SUBSCRIBE's per_frame), whatever
    front ends it serves."""
    from emulator.frontends import capabilities
    from protocol.constants import CAP_BATCH

    assert all(capabilities(m, c) & CAP_BATCH for m in (False, True) for c in (False, True))
