"""Helpers for the protocol tests on both interpreters: feeding bytes in every way.

``FEEDS`` names the three ways every codec test feeds its input: all at once, one byte at
a time, and with garbage in front (``chunks`` splits the input so). ``feed`` returns the
events a connection yields for ``data`` fed in one of those ways, with the garbage report of
the prefix left out.
"""

from protocol.connection import BOARD, HOST, Connection
from protocol.constants import E_GARBAGE
from protocol.framing import BadFrame
from protocol.messages import Hello

KEY = bytes(range(32))
NONCE = bytes(range(0xA0, 0xB0))
GARBAGE = b"\x00\xffnoise\xdb\x01\xdb"  # includes a false start marker byte
FEEDS = ("whole", "bytewise", "garbage")


def hello(nonce: bytes = NONCE) -> Hello:
    return Hello(1, "test-board", "0.1.0", 10, 0x7F, 0x01020304, nonce, 0, 0)


def pair(key: bytes = KEY) -> "tuple[Connection, Connection]":
    """A board and a host connection in session with each other."""
    board = Connection(BOARD, key)
    host = Connection(HOST, key)
    host.receive_data(board.send(hello()))
    got = host.events()
    assert len(got) == 1 and isinstance(got[0], Hello)
    return board, host


def chunks(data: bytes, how: str) -> "list[bytes]":
    """``data`` as the feed ``how`` delivers it: whole, one byte at a time, or after garbage."""
    if how == "garbage":
        data = GARBAGE + data
    if how == "bytewise":
        return [data[i : i + 1] for i in range(len(data))]
    return [data]


def feed(conn: Connection, data: bytes, how: str) -> list:  # type: ignore[type-arg]
    events = []
    for chunk in chunks(data, how):
        conn.receive_data(chunk)
        events.extend(conn.events())
    if how == "garbage":
        if not (events and isinstance(events[0], BadFrame) and events[0].code == E_GARBAGE):
            raise AssertionError("garbage in front was not reported first: %r" % (events,))
        events = events[1:]
    return events
