"""The firmware's network front end (``firmware/net.py``) with readings batched (SUBSCRIBE's
``per_frame``), on the test HAL's simulated clock: a client that reads gets every reading, k
a frame, none lost; a client that does not read has its readings skipped (the gap shows in
``seq`` once it reads again) and is never disconnected for it; the one never holds up the
other. And the emulator's HELLO offers the capability.
"""

from __future__ import annotations

import asyncio
import itertools

from emulator.frontends import BASE_CAPS, capabilities
from firmware.net import HARD_CAP, Net
from protocol.connection import HOST, Connection
from protocol.constants import CAP_BATCH
from protocol.messages import Measurement, MeasurementBatch, Subscribe
from tests.emulator.test_net import _Blocked
from tests.emulator.wire import KEY
from tests.firmware.testhal import Rig


def _readings(conn: Connection, data: bytes) -> tuple[list[int], list[int]]:
    """The seq of every reading in ``data``, and the number of readings in each frame."""
    seqs: list[int] = []
    sizes: list[int] = []
    for i in range(0, len(data), 1024):
        conn.receive_data(data[i:i + 1024])
        for m in conn.events():
            if isinstance(m, MeasurementBatch):
                seqs.extend(r.seq for r in m.readings)
                sizes.append(len(m.readings))
            elif isinstance(m, Measurement):
                seqs.append(m.seq)
                sizes.append(1)
    return seqs, sizes


def test_the_emulator_offers_batching() -> None:
    assert BASE_CAPS & CAP_BATCH
    assert capabilities(True, True) & CAP_BATCH


async def test_batches_for_a_reader_skips_for_a_stuck_writer() -> None:
    rig = Rig(board={"key": KEY.hex()})
    net = Net(rig.app, "test", CAP_BATCH)
    stuck, free = _Blocked(), _Blocked()
    free.go.set()
    conns = []
    tasks = []
    for w in (stuck, free):
        reader = asyncio.StreamReader()
        conn = Connection(HOST, KEY)
        tasks.append(asyncio.create_task(net.serve_stream(reader, w)))
        await asyncio.sleep(0)
        reader.feed_data(conn.send(Subscribe(100, per_frame=4, req_id=1)))
        conns.append(conn)
    for _ in range(1000):  # 10 simulated seconds
        rig.run(10)
        net.pump(rig.hal.now)
        await asyncio.sleep(0)
    stuck_client = next(c for c in net.clients if c.writer is stuck)
    assert stuck_client.skipped > 900
    assert stuck_client.n <= HARD_CAP and not stuck_client.closed
    seqs, sizes = _readings(conns[1], bytes(free.data))
    assert seqs == list(range(1, 1001))
    assert sizes == [4] * 250
    stuck.go.set()  # the peer reads at last: what it gets shows the gap
    for _ in range(8):
        rig.run(10)
        net.pump(rig.hal.now)
        await asyncio.sleep(0)
    got, sizes = _readings(conns[0], bytes(stuck.data))
    assert got[0] < 100 and got[-1] > 1000
    assert any(b - a > 1 for a, b in itertools.pairwise(got))
    assert max(sizes) <= 4
    for t in tasks:
        t.cancel()
