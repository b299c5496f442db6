# cpython-only: hypothesis does not run on MicroPython
"""Property test: at least 100,000 random and mutated frames, split at random, never make
the codec raise; every event is a message or a ``BadFrame``; the messages found do not
depend on how the bytes were split; a good frame after the damage is still decoded; and a
MEASUREMENT_BATCH that decodes is a whole one (1-10 readings of one channel count).
"""

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from protocol import messages as m
from protocol.connection import BOARD, HOST, Connection
from protocol.framing import BadFrame
from tests.protocol.mutations import damaged
from tests.protocol.samples import later_samples, samples
from tests.protocol.util import KEY, hello

FRAMES_PER_EXAMPLE = 40
EXAMPLES = 2500  # x 40 = 100,000 frames

_board = Connection(BOARD, KEY)
_host = Connection(HOST, KEY)
_host.receive_data(_board.send(hello()))
_host.events()
# Valid frames of every message in both directions, signed ones included.
VALID = [(_board if s.DIR == "B" else _host).send(s) for s in samples() + later_samples()]
TRAILER = _board.send(m.Pong(0xABCD, 1, req_id=1))


def _decode(role: str, data: bytes, cuts: "list[int]") -> "list[object]":
    conn = Connection(role, KEY)
    if role == BOARD:
        conn.send(hello())
    else:
        conn.receive_data(_board.send(hello()))
        conn.events()
    events: list[object] = []
    prev = 0
    for cut in [*sorted(c % (len(data) + 1) for c in cuts), len(data)]:
        if cut > prev:  # an empty chunk would mean the end of the stream
            conn.receive_data(data[prev:cut])
            events.extend(conn.events())
            prev = cut
    conn.receive_data(b"")
    events.extend(conn.events())
    return events


# 100,000 frames are CPU work: on a shared machine at a load of 30 they take minutes, so
# this test gets a longer limit than the suite's 300 s.
@pytest.mark.timeout(1800)
@settings(
    max_examples=EXAMPLES,
    derandomize=True,
    deadline=None,
    suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large],
)
@given(
    frames=damaged(VALID, b"\xdb\x58", FRAMES_PER_EXAMPLE),
    cuts=st.lists(st.integers(0, 1 << 16), max_size=12),
    role=st.sampled_from([BOARD, HOST]),
)
def test_nothing_escapes(frames: "list[bytes]", cuts: "list[int]", role: str) -> None:
    data = b"".join(frames) + b"\x00" * 8 + TRAILER
    split = _decode(role, data, cuts)
    whole = _decode(role, data, [])
    for ev in split:
        assert isinstance(ev, (m.Message, BadFrame))
        if isinstance(ev, m.MeasurementBatch):  # whole or not at all: never a partial batch
            assert 1 <= len(ev.readings) <= 10
            assert len({len(r.currents_ma) for r in ev.readings}) == 1
    assert [e for e in split if isinstance(e, m.Message)] == [
        e for e in whole if isinstance(e, m.Message)
    ]
    if role == HOST:  # the trailer is a board message: the host must still decode it
        assert split[-1] == m.Pong(0xABCD, 1, req_id=1)
