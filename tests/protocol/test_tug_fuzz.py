# cpython-only: hypothesis does not run on MicroPython
"""Property test of the tug decoder: 30,000 random and mutated frames in both directions,
split at random, never make it raise; every event is a ``Frame`` or a ``Bad``; the frames
found do not depend on how the bytes were split; a good frame after the damage and a run of
zeros longer than any frame (the format has no checksum: a cut header waits for its
payload) still decodes; and on the board's side no CHANNEL frame with a valid state comes
out that was not sent whole.
"""

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from protocol import tug as tw
from tests.protocol.mutations import damaged

FRAMES_PER_EXAMPLE = 25
EXAMPLES = 1200  # x 25 = 30,000 frames

SENT = {
    tw.FROM_HOST: [tw.set_frequency(200), tw.request(), bytes([2, 3, 0, 0, 2]),
                   tw.channel(3, True), tw.channel(7, False)],
    tw.FROM_BOARD: [tw.specs([(1.0, 24.0)] * 10), tw.ack(0), tw.ack(4),
                    tw.measurements([(1, 0.5, 24.0), (0, 0.0, 0.0)] * 5)],
}
TRAILER = {tw.FROM_HOST: tw.channel(9, True), tw.FROM_BOARD: tw.ack(6)}


def decode(accept: tuple[int, ...], data: bytes, cuts: list[int]) -> list[object]:
    d = tw.TugDecoder(accept)
    out: list[object] = []
    prev = 0
    for cut in [*sorted(c % (len(data) + 1) for c in cuts), len(data)]:
        d.feed(data[prev:cut])
        out += d.frames()
        prev = cut
    return out


# 100,000 frames are CPU work: on a shared machine at a load of 30 they take minutes, so
# this test gets a longer limit than the suite's 300 s.
@pytest.mark.timeout(1800)
@settings(max_examples=EXAMPLES, derandomize=True, deadline=None,
          suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large])
@given(data=st.data(), cuts=st.lists(st.integers(0, 1 << 16), max_size=10),
       accept=st.sampled_from([tw.FROM_HOST, tw.FROM_BOARD]))
def test_nothing_escapes(data: st.DataObject, cuts: list[int],
                         accept: tuple[int, ...]) -> None:
    frames = data.draw(damaged(SENT[accept], b"\x02", FRAMES_PER_EXAMPLE))
    stream = b"".join(frames) + bytes(tw.HEADER_LEN + tw.MAX_PAYLOAD) + TRAILER[accept]
    split = decode(accept, stream, cuts)
    whole = decode(accept, stream, [])
    assert all(isinstance(e, (tw.Frame, tw.Bad)) for e in split)
    assert [e for e in split if isinstance(e, tw.Frame)] == [
        e for e in whole if isinstance(e, tw.Frame)]
    assert split[-1] == tw.Frame(TRAILER[accept][1], TRAILER[accept][4:])
    for e in split:
        if isinstance(e, tw.Frame) and e.command == tw.CHANNEL and e.payload[1] <= 1:
            assert tw.encode(tw.CHANNEL, e.payload) in stream
