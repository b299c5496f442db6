"""A bounded event log that protection writes and front ends read, without ever blocking.

Each event is a tuple ``(seq, kind, channel, old_state, new_state, faults, value_ma,
uptime_ms)``: ``kind`` an ``EV_*``, ``channel`` 0..n-1 or ``BOARD_CHANNEL``, the states
``ST_*`` (equal for non-state events), ``faults`` the ``F_*`` (or ``B_*`` for board events)
involved, ``value_ma`` the current that caused it; a board event (channel ``BOARD_CHANNEL``)
carries the board flags after the change in ``faults`` and the input voltage (mV) in
``value_ma`` (``protocol/events.py`` names all of it, for every reader). ``EV_REBOOT``
carries the reset cause (``RESET_*``) in ``old_state`` and the configuration status (``CFG_*``)
in ``new_state``. ``seq`` counts from 1 and never repeats within a boot.

The log is a ring of ``size`` slots. Writing never waits and never fails: when the ring is
full the oldest event is overwritten. Every reader keeps its own cursor (the last ``seq`` it
has seen, 0 at first) and calls ``read(cursor, max_n)``; it gets the events after its cursor,
its next cursor, and how many events it lost because they were overwritten before it read
them, so several front ends drain the same log independently and each can report its loss.
"""


if False:  # typing only; MicroPython never imports typing (the block is compiled away)
    from typing import Any

    # (seq, kind, channel, old, new, faults, value, uptime), as ``put`` logs it
    EventRow = tuple[int, int, int, int, int, int, int, int]


class EventLog:
    def __init__(self, size: int = 64) -> None:
        self.size = size
        self.ring: "list[Any]" = [None] * size  # an EventRow, or None where none was put yet
        self.seq = 0  # seq of the newest event

    def put(self, kind: int, ch: int, old: int, new: int, faults: int, value: int,
            uptime: int) -> None:
        self.seq += 1
        self.ring[self.seq % self.size] = (self.seq, kind, ch, old, new, faults, value, uptime)

    def read(self, cursor: int, max_n: int = 16) -> "tuple[list[EventRow], int, int]":
        """``(events, next_cursor, lost)`` for a reader that has seen up to ``cursor``."""
        oldest = self.seq - self.size + 1
        lost = 0
        if cursor < oldest - 1:
            lost = oldest - 1 - cursor
            cursor = oldest - 1
        if cursor > self.seq:  # a cursor from an earlier boot: start over
            cursor = 0 if self.seq < self.size else oldest - 1
        out: "list[EventRow]" = []
        s = cursor + 1
        while s <= self.seq and len(out) < max_n:
            out.append(self.ring[s % self.size])
            s += 1
        return out, s - 1, lost
