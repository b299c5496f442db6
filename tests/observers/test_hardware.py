"""The hardware observer fed with the board client's own value types (``host.board.types``)."""

from __future__ import annotations

import pytest

from host.board.types import BoardEvent, LinkDown, Reading, Rebooted
from host.observers import Device, HardwareObserver, Retraction
from protocol.constants import EV_STATE, EV_TRIP, ST_LATCHED, ST_OFF, ST_ON, ST_TRIPPED

HOKUYO = Device("hokuyo", 3, (0.2, 1.2))
JAGUAR = Device("jaguar", 7, (0.5, 10.0))


def reading(seq: int, on: dict[int, int], t: float = 0.0) -> Reading:
    currents = tuple(on.get(ch, 0) for ch in range(10))
    mask = sum(1 << ch for ch, ma in on.items() if ma is not None)
    return Reading(t, t, 1, seq, seq * 10, 12000, mask, 0, currents)


def event(kind: int, ch: int, old: int, new: int) -> BoardEvent:
    return BoardEvent(0.0, 1, 5, 100, kind, ch, old, new, 0, 0, 0)


def lits(updates: list) -> list[tuple[str, float]]:
    return [(u.atom if isinstance(u, Retraction) else str(u.literal), u.time) for u in updates]


def test_on_band_with_settle_and_trip() -> None:
    h = HardwareObserver({"hokuyo": HOKUYO, "jaguar": JAGUAR}, link_timeout=0.05, settle=3)
    out = h.feed(reading(1, {3: 500}), 1.00)
    assert sorted(lits(out)) == [("link(board)", 1.0), ("on(hokuyo)", 1.0),
                                 ("~on(jaguar)", 1.0)]
    out = h.feed(reading(2, {3: 500}), 1.01) + h.feed(reading(3, {3: 500}), 1.02)
    assert lits(out) == [("in_band(hokuyo)", 1.02)]  # the third agreeing reading
    # one spike does not flip it; three do
    out = h.feed(reading(4, {3: 2500}), 1.03) + h.feed(reading(5, {3: 500}), 1.04)
    assert out == []
    out = []
    for i, t in enumerate((1.05, 1.06, 1.07)):
        out += h.feed(reading(6 + i, {3: 2500}), t)
    assert lits(out) == [("~in_band(hokuyo)", 1.07)] and h.bands["hokuyo"] == "over"
    # the board trips the channel: an event, then readings with the switch off
    out = h.feed(event(EV_TRIP, 3, ST_ON, ST_TRIPPED), 1.08)
    assert lits(out) == [("tripped(hokuyo)", 1.08)]
    out = h.feed(reading(9, {}), 1.09)
    assert sorted(lits(out)) == [("in_band(hokuyo)", 1.09), ("~on(hokuyo)", 1.09)]
    assert isinstance(out[-1], Retraction)  # a switched-off device has no band: unknown
    out = h.feed(event(EV_STATE, 3, ST_TRIPPED, ST_LATCHED), 1.10)
    assert out == []  # still tripped (now latched)
    out = h.feed(event(EV_STATE, 3, ST_LATCHED, ST_OFF), 1.11)  # cleared
    assert lits(out) == [("~tripped(hokuyo)", 1.11)]


def test_link_lost_makes_device_literals_unknown() -> None:
    h = HardwareObserver({"hokuyo": HOKUYO}, link_timeout=0.05, settle=1)
    h.feed(reading(1, {3: 500}), 2.0)
    assert h.asserted == {"link(board)": True, "on(hokuyo)": True, "in_band(hokuyo)": True}
    assert h.next_deadline() == pytest.approx(2.05)
    out = h.tick(2.05)  # readings stopped: the link is judged dead at its deadline
    assert sorted(lits(out)) == [("in_band(hokuyo)", 2.05), ("on(hokuyo)", 2.05),
                                 ("~link(board)", 2.05)]
    assert h.asserted == {"link(board)": False}
    assert h.next_deadline() == pytest.approx(3.05)  # refresh of ~link only
    out = h.feed(reading(2, {3: 500}), 3.0)  # back
    assert h.asserted["link(board)"] is True and h.asserted["on(hokuyo)"] is True
    out = h.feed(LinkDown(3.01, "eof"), 3.01)  # an explicit notice acts at once
    assert sorted(lits(out)) == [("in_band(hokuyo)", 3.01), ("on(hokuyo)", 3.01),
                                 ("~link(board)", 3.01)]


def test_reboot_forgets_trips_and_link_atom_can_be_left_out() -> None:
    h = HardwareObserver({"jaguar": JAGUAR}, link_atom=None)
    h.feed(event(EV_TRIP, 7, ST_ON, ST_TRIPPED), 1.0)
    assert h.asserted == {"tripped(jaguar)": True}
    out = h.feed(Rebooted(1.5, 1, 2, 1, "boot id"), 1.5)
    assert lits(out) == [("tripped(jaguar)", 1.5)] and h.asserted == {}
    assert "link(board)" not in h.atoms()
