"""The tests' own host end (``tests.emulator.wire.Wire``) under a backlog.

On a loaded machine a test's client may be descheduled while the board keeps sending: one read
then returns tens of kilobytes, more than a ``Decoder`` takes undrained (``BUFFER_CAP``, eight
frames). Found in a suite run beside a CPU hog (``receive buffer full`` in
``test_four_clients_at_100hz_no_gaps_while_garbage``): the client must feed what it reads in
pieces, as the host's transports do.
"""

from __future__ import annotations

import asyncio

from protocol.framing import BUFFER_CAP, BadFrame
from tests.emulator.wire import READ_SIZE, Wire


async def test_a_backlog_larger_than_the_decoders_buffer_is_read_in_pieces() -> None:
    reader = asyncio.StreamReader()
    reader.feed_data(b"\x00" * (4 * BUFFER_CAP))  # a backlog of bytes, all at once
    reader.feed_eof()
    wire = Wire(reader, None, key=None)  # type: ignore[arg-type]  # nothing is sent
    got = await wire.next(lambda m: isinstance(m, BadFrame), timeout=5.0)
    assert isinstance(got, BadFrame)
    assert READ_SIZE + BUFFER_CAP // 8 <= BUFFER_CAP  # a read and a frame's tail fit
