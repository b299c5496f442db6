"""The hardware observer fed with the board client's own value types (``host.board.types``).

What the board says is believed once it agrees with itself: ``on``, ``in_band`` and the health a
reading shows change only after ``settle`` consecutive readings agree, and a trip reported by an
event counts once the readings confirm it (a real trip switches the channel off and leaves a live
fault). So a single frame that lies with a valid checksum changes nothing.
"""

from __future__ import annotations

import pytest

from host.board.types import BoardEvent, BoardState, ChannelState, LinkDown, Reading, Rebooted
from host.observers import Device, HardwareObserver, Retraction
from host.observers.silence import JITTER_S
from protocol.constants import (
    EV_FAULT,
    EV_STATE,
    EV_TRIP,
    F_SHORT,
    F_STUCK_ON,
    ST_FAULTED,
    ST_LATCHED,
    ST_OFF,
    ST_ON,
    ST_TRIPPED,
)

HOKUYO = Device("hokuyo", 3, (0.2, 1.2))
JAGUAR = Device("jaguar", 7, (0.5, 10.0))


def reading(seq: int, on: dict[int, int], t: float = 0.0, faults: int = 0) -> Reading:
    """Channels in ``on`` read back on with their current (mA); ``faults``: the live mask."""
    currents = tuple(on.get(ch, 0) for ch in range(10))
    mask = sum(1 << ch for ch, ma in on.items() if ma is not None)
    return Reading(t, t, 1, seq, seq * 10, 12000, mask, faults, currents)


def event(kind: int, ch: int, old: int, new: int) -> BoardEvent:
    return BoardEvent(0.0, 1, 5, 100, kind, ch, old, new, 0, 0, 0)


def state(states: dict[int, tuple[bool, int, int]]) -> BoardState:
    """A STATE: channel -> (switch on, state, live faults); the others off and idle."""
    chans = []
    for ch in range(10):
        on, st, live = states.get(ch, (False, ST_OFF, 0))
        chans.append(ChannelState(ch, f"ch{ch}", on, on, st, 500 if on else 0, live, 0, 0, 0))
    return BoardState(0.0, 1, 1000, 12000, 500, 0, 0, 0, tuple(chans))


def lits(updates: list) -> list[tuple[str, float]]:
    return [(u.atom if isinstance(u, Retraction) else str(u.literal), u.time) for u in updates]


def feed_readings(h: HardwareObserver, t0: float, n: int, on: dict[int, int],
                  faults: int = 0, seq0: int = 100) -> list:
    out: list = []
    for i in range(n):
        t = round(t0 + i * 0.01, 3)
        out += h.feed(reading(seq0 + i, on, t, faults), t)
    return out


def healthy_hokuyo(settle: int = 3) -> HardwareObserver:
    h = HardwareObserver({"hokuyo": HOKUYO, "jaguar": JAGUAR}, link_timeout=0.05, settle=settle)
    feed_readings(h, 1.0, settle, {3: 500})
    assert h.asserted == {"link(board)": True, "on(hokuyo)": True, "in_band(hokuyo)": True,
                          "tripped(hokuyo)": False, "on(jaguar)": False,
                          "tripped(jaguar)": False}
    return h


def test_on_and_band_need_settle_agreeing_readings() -> None:
    h = HardwareObserver({"hokuyo": HOKUYO, "jaguar": JAGUAR}, link_timeout=0.05, settle=3)
    out = h.feed(reading(1, {3: 500}), 1.00)
    assert lits(out) == [("link(board)", 1.0)]  # one reading alone is believed in nothing
    out = h.feed(reading(2, {3: 500}), 1.01) + h.feed(reading(3, {3: 500}), 1.02)
    assert sorted(lits(out)) == [("in_band(hokuyo)", 1.02), ("on(hokuyo)", 1.02),
                                 ("~on(jaguar)", 1.02), ("~tripped(hokuyo)", 1.02),
                                 ("~tripped(jaguar)", 1.02)]  # the third agreeing reading
    # one spike does not flip the band; three do
    out = h.feed(reading(4, {3: 2500}), 1.03) + h.feed(reading(5, {3: 500}), 1.04)
    assert out == []
    out = feed_readings(h, 1.05, 3, {3: 2500})
    assert lits(out) == [("~in_band(hokuyo)", 1.07)] and h.bands["hokuyo"] == "over"
    # switched off: three readings later on(hokuyo) is false and its band unknown
    out = feed_readings(h, 1.08, 3, {})
    assert sorted(lits(out)) == [("in_band(hokuyo)", 1.1), ("~on(hokuyo)", 1.1)]
    assert isinstance(out[-1], Retraction)  # a switched-off device has no band: unknown
    # and on again: its band is judged from the same readings as its switch
    out = feed_readings(h, 1.2, 3, {3: 500})
    assert sorted(lits(out)) == [("in_band(hokuyo)", 1.22), ("on(hokuyo)", 1.22)]


def test_a_lying_measurement_changes_nothing() -> None:
    h = healthy_hokuyo()
    before = h.asserted
    # one frame with a valid checksum says the lidar is off, draws nothing, has a live fault
    out = h.feed(reading(50, {}, 1.5, faults=1 << 3), 1.5)
    out += feed_readings(h, 1.51, 2, {3: 500})
    out += h.feed(reading(60, {}, 1.6, faults=1 << 3), 1.6)  # and again, once, later
    out += feed_readings(h, 1.61, 5, {3: 500})
    assert out == [] and h.asserted == before


def test_a_lying_trip_event_is_not_believed() -> None:
    h = healthy_hokuyo()
    before = h.asserted
    out = h.feed(event(EV_TRIP, 3, ST_ON, ST_TRIPPED), 1.5)  # the hokuyo "tripped"...
    out += feed_readings(h, 1.51, 10, {3: 500})  # ...but it stays on, no live fault
    assert out == [] and h.asserted == before
    # and the claim is forgotten: a later switch-off with a fault does not revive it
    out = feed_readings(h, 1.7, 5, {}, faults=1 << 3)
    assert ("tripped(hokuyo)", 1.72) not in lits(out)


def test_a_real_trip_is_confirmed_by_the_readings() -> None:
    # the board trips the channel: an event, one reading that still shows the switch on (its
    # read-back lags a tick), then readings with the switch off and the fault live
    h = healthy_hokuyo()
    assert h.feed(event(EV_TRIP, 3, ST_ON, ST_TRIPPED), 1.50) == []
    assert not h.confirmed("tripped(hokuyo)")  # a claim is no finding yet
    out = h.feed(reading(7, {3: 2500}, 1.505, faults=1 << 3), 1.505)
    out += feed_readings(h, 1.51, 3, {}, faults=1 << 3)
    assert ("tripped(hokuyo)", 1.53) in lits(out)  # the third reading off with the fault
    assert ("~on(hokuyo)", 1.53) in lits(out)
    # a confirmed finding: the repair service need not debounce it (``Observer.confirmed``)
    assert h.confirmed("tripped(hokuyo)") and not h.confirmed("on(hokuyo)")
    assert not h.confirmed("tripped(jaguar)")
    out = h.feed(event(EV_STATE, 3, ST_TRIPPED, ST_LATCHED), 1.54)
    out += feed_readings(h, 1.55, 3, {}, faults=1 << 3)
    assert out == []  # still tripped (now latched)
    out = h.feed(event(EV_STATE, 3, ST_LATCHED, ST_OFF), 1.6)  # cleared
    assert lits(out) == [("~tripped(hokuyo)", 1.6)]


def test_a_stuck_switch_fault_is_confirmed_with_the_switch_on() -> None:
    h = healthy_hokuyo()
    feed_readings(h, 1.1, 3, {})  # switched off by the host
    assert h.feed(event(EV_FAULT, 3, ST_OFF, ST_FAULTED), 1.2) == []
    out = feed_readings(h, 1.21, 3, {3: 400}, faults=1 << 3)  # current flows: stuck on
    assert ("tripped(hokuyo)", 1.23) in lits(out)


def test_literals_recover_with_fresh_readings_after_a_silence() -> None:
    h = healthy_hokuyo()
    assert h.tick(1.1) == []  # the readings stopped: the gap is noticed at its deadline...
    h.tick(1.1 + JITTER_S)  # ...and the link judged dead by a tick of an awake loop
    assert h.asserted == {"link(board)": False}
    out = feed_readings(h, 3.0, 3, {3: 500})  # back, without a reconnect (no new STATE)
    assert h.asserted == {"link(board)": True, "on(hokuyo)": True, "in_band(hokuyo)": True,
                          "tripped(hokuyo)": False, "on(jaguar)": False,
                          "tripped(jaguar)": False}
    assert ("~tripped(hokuyo)", 3.02) in lits(out)  # no live fault: not tripped


def test_a_state_is_believed_at_once() -> None:
    h = HardwareObserver({"hokuyo": HOKUYO, "jaguar": JAGUAR}, link_timeout=0.05, settle=3)
    out = h.feed(state({3: (True, ST_ON, 0), 7: (False, ST_LATCHED, F_SHORT)}), 1.0)
    assert h.asserted == {"link(board)": True, "on(hokuyo)": True, "tripped(hokuyo)": False,
                          "on(jaguar)": False, "tripped(jaguar)": True}
    # the switch read back off with a live fault, as the STATE said: nothing changes
    out = feed_readings(h, 1.01, 3, {3: 500}, faults=1 << 7)
    assert lits(out) == [("in_band(hokuyo)", 1.03)]
    out = h.feed(state({3: (True, ST_FAULTED, F_STUCK_ON)}), 1.1)
    assert sorted(lits(out)) == [("tripped(hokuyo)", 1.1), ("~tripped(jaguar)", 1.1)]


def test_link_lost_makes_device_literals_unknown() -> None:
    h = HardwareObserver({"hokuyo": HOKUYO}, link_timeout=0.05, settle=1)
    h.feed(reading(1, {3: 500}), 2.0)
    assert h.asserted == {"link(board)": True, "on(hokuyo)": True, "in_band(hokuyo)": True,
                          "tripped(hokuyo)": False}
    assert h.next_deadline() == pytest.approx(2.05)
    assert h.tick(2.05) == []  # readings stopped: the gap is noticed at its deadline...
    assert h.next_deadline() == pytest.approx(2.05 + JITTER_S)
    out = h.tick(2.07)  # ...and confirmed by an on-time tick: the link is judged dead
    assert sorted(lits(out)) == [("in_band(hokuyo)", 2.07), ("on(hokuyo)", 2.07),
                                 ("tripped(hokuyo)", 2.07), ("~link(board)", 2.07)]
    assert h.asserted == {"link(board)": False}
    assert h.next_deadline() == pytest.approx(3.07)  # refresh of ~link only
    out = h.feed(reading(2, {3: 500}), 3.0)  # back
    assert h.asserted["link(board)"] is True and h.asserted["on(hokuyo)"] is True
    out = h.feed(LinkDown(3.01, "eof"), 3.01)  # an explicit notice acts at once
    assert sorted(lits(out)) == [("in_band(hokuyo)", 3.01), ("on(hokuyo)", 3.01),
                                 ("tripped(hokuyo)", 3.01), ("~link(board)", 3.01)]


def test_reboot_forgets_trips_and_link_atom_can_be_left_out() -> None:
    h = HardwareObserver({"jaguar": JAGUAR}, link_atom=None, settle=1)
    h.feed(reading(1, {7: 2000}), 0.9)
    h.feed(event(EV_TRIP, 7, ST_ON, ST_TRIPPED), 1.0)
    h.feed(reading(2, {}, 1.01, faults=1 << 7), 1.01)
    assert h.asserted["tripped(jaguar)"] is True
    out = h.feed(Rebooted(1.5, 1, 2, 1, "boot id"), 1.5)
    assert lits(out) == [("tripped(jaguar)", 1.5)] and "tripped(jaguar)" not in h.asserted
    assert "link(board)" not in h.atoms()
