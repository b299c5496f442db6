"""The board's link rule on a loaded machine, on a simulated clock: late is not lost.

The hardware observer declares the link lost after ``link_timeout`` without a reading. On a busy
machine readings come late (the board's process or the daemon's loop descheduled) yet still
stamped by the board every period: that is no lost link. ``Loaded`` (``tests.observers.loaded``)
plays the hub's part; the board stamps each reading with its own uptime. A board that truly
falls silent is still found within its bound (``link_timeout + link_slack``).
"""

from __future__ import annotations

import functools

import pytest

from host.board.types import LinkDown, Reading
from host.observers import Device, HardwareObserver
from host.observers.silence import JITTER_MEMORY_S, JITTER_S
from tests.observers.loaded import Loaded, Send, stalls

HOKUYO = Device("hokuyo", 3, (0.2, 1.2))
LINK = "link(board)"
PERIOD = 0.01  # 100 Hz, as the daemon subscribes
TIMEOUT = 0.25  # system.yaml's link_timeout


def reading(seq: int, sent: float, arrival: float) -> Reading:
    """Reading ``seq`` stamped by the board at ``sent`` (its uptime), read at ``arrival``."""
    currents = tuple(500 if ch == 3 else 0 for ch in range(10))
    return Reading(arrival, arrival, 1, seq, round(sent * 1000), 12000, 1 << 3, 0, currents)


def board(start: float, end: float, seq0: int = 1) -> list[Send]:
    """The board's readings every period from ``start`` to ``end``."""
    n = round((end - start) / PERIOD)
    return [(start + k * PERIOD, functools.partial(reading, seq0 + k, start + k * PERIOD))
            for k in range(n)]


def observer() -> HardwareObserver:
    return HardwareObserver({"hokuyo": HOKUYO}, link_timeout=TIMEOUT, settle=3)


@pytest.mark.parametrize("seed", [1, 2, 3])
def test_a_stalled_daemon_loop_is_not_a_lost_link(seed: int) -> None:
    # the consumer stalls up to 0.5 s (twice the timeout): its timer fires late, before the
    # readings that queued meanwhile are fed; the board was never silent
    h = observer()
    sim = Loaded(h, stalls(seed, 60.0, 0.5))
    sim.run(board(0.0, 60.0), 60.0)
    assert [v for v, _ in sim.verdicts(LINK)] == [True]


def test_late_but_stamped_readings_are_learned_and_not_a_lost_link() -> None:
    # the board's process is descheduled now and then while the daemon is awake: readings
    # arrive late and bunched, stamped when due. Up to 0.2 s (within the timeout) first, then
    # up to 0.4 s: tolerated, as twice the longest gap seen lately
    h = observer()
    delayed = [(a, a + 0.8 * (b - a)) for a, b in stalls(6, 20.0, 0.25)]
    delayed += [(a, b) for a, b in stalls(7, 50.0, 0.4) if a > 20.0]
    sim = Loaded(h, [], delayed)
    sim.run(board(0.0, 50.0), 50.0)
    assert [v for v, _ in sim.verdicts(LINK)] == [True]
    assert TIMEOUT < h.link_limit <= TIMEOUT + h.link_slack
    # a busy spell is forgotten after a quiet minute: fast detection again
    sim.run(board(50.0, 50.0 + JITTER_MEMORY_S + 1.0, seq0=5001), 50.0 + JITTER_MEMORY_S + 1.0)
    assert h.link_limit == TIMEOUT


def test_a_silent_board_on_an_idle_daemon_is_lost_at_the_timeout_and_confirmed() -> None:
    h = observer()
    sim = Loaded(h, [])
    sim.run(board(0.0, 2.0), 3.0)
    last = 2.0 - PERIOD
    assert sim.verdicts(LINK) == [(True, pytest.approx(0.0)),
                                  (False, pytest.approx(last + TIMEOUT + JITTER_S))]
    # every device literal is unknown with the link gone
    assert h.asserted == {LINK: False}


@pytest.mark.parametrize("seed", [4, 5])
def test_a_silent_board_is_found_within_its_bound_despite_stalls_and_delays(seed: int) -> None:
    h = observer()
    delayed = stalls(seed, 30.0, 0.4)
    sim = Loaded(h, stalls(seed + 10, 40.0, 0.3), delayed)
    sim.run(board(0.0, 30.0), 40.0)
    got = sim.verdicts(LINK)
    assert [v for v, _ in got] == [True, False]
    last = sim.arrives(30.0 - PERIOD)  # the last reading, read by the daemon
    assert last + TIMEOUT <= got[1][1] <= sim.resumed(last + TIMEOUT + h.link_slack)


def test_a_gap_ended_by_a_reconnect_is_not_learned() -> None:
    # a lost link that came back through the client's reconnect (LinkDown, LinkUp) says
    # nothing about how late readings come: the limit stays at the timeout
    h = observer()
    sim = Loaded(h, [])
    sim.run(board(0.0, 1.0), 1.0)
    sim.updates += h.feed(LinkDown(1.1, "eof"), 1.1)
    sim.run(board(3.0, 4.0, seq0=1), 4.0)
    assert h.link_limit == TIMEOUT
