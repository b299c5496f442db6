"""``RangeEvents``: on a wire without events (Modbus, CAN) the host's transport makes the
``low`` flag's range EVENTs (PROTOCOL.md section 10) from the live flags of two polls: one
when the flag comes, one when it goes, none while it stays. ``dxboard board status`` shows such
a channel's current as low, not measured, and not as a fault."""

from __future__ import annotations

from host.transports.translate import RangeEvents
from protocol.constants import EV_RANGE, F_LOW, F_OPEN_LOAD, ST_ON


def test_one_event_each_way_and_none_while_it_stays() -> None:
    r = RangeEvents()
    states, currents = [ST_ON] * 3, [500, 0, 300]
    assert r.changes(10, [0, 0, 0], states, currents) == []
    (came,) = r.changes(20, [0, F_LOW, F_OPEN_LOAD], states, currents)
    assert (came.kind, came.channel, came.old_state, came.new_state, came.faults,
            came.value_ma, came.uptime_ms) == (EV_RANGE, 1, ST_ON, ST_ON, F_LOW, 0, 20)
    assert r.changes(30, [0, F_LOW, 0], states, currents) == []
    (went,) = r.changes(40, [0, 0, 0], states, [500, 140, 300])
    assert (went.channel, went.faults, went.value_ma) == (1, 0, 140)
    assert went.seq > came.seq


def test_the_status_table_says_low_not_measured_not_a_fault() -> None:
    from host.commands.board import format_status

    info = {"board_id": "b", "firmware": "f", "boot_id": 1, "url": "tcp://h:7000"}
    chan = {"channel": 6, "name": "thermal_camera", "state": "on", "current_ma": 0,
            "live_faults": ["low"], "sticky_faults": []}
    state = {"uptime_ms": 1000, "input_mv": 12000, "total_ma": 0, "board_flags": [],
             "config_status": "ok", "channels": [chan]}
    lines = format_status(info, state).splitlines()
    row = next(line for line in lines if "thermal_camera" in line)
    assert row.split()[-3:] == ["low", "*", "-"]  # no fault listed, no 0.000 A
    assert lines[-1].startswith("* low, not measured")


async def test_the_can_transport_pushes_the_event_before_the_reading() -> None:
    """CAN carries each channel's live flags in DXB_Channel but no events: the transport makes
    the range EVENT from them, before the DXB_Currents reading that completes the tick."""
    from host.transports.can import CanTransport
    from host.transports.url import parse
    from protocol import can as layout
    from protocol.messages import Event, Measurement

    t = CanTransport(parse("can://virtual/dxb-range-test"))
    pushed: list[object] = []
    t.push = pushed.append  # type: ignore[method-assign, assignment]
    t.n, t._subscribed = 2, True
    commanded, physical, trips, retries = True, True, 0, 0
    for live in (0, F_LOW, F_LOW, 0):
        for k in range(2):
            flags = live if k == 1 else 0
            t._frame(layout.channel_id(0, k), layout.channel_frame(
                (commanded, physical, ST_ON, 0, flags, 0, trips, retries)))
        t._frame(layout.currents_id(0, 0), layout.currents_frame([500, 0, 0, 0], 0))
    kinds = [(type(m).__name__, getattr(m, "faults", None)) for m in pushed]
    assert kinds == [("Measurement", None), ("Event", F_LOW), ("Measurement", None),
                     ("Measurement", None), ("Event", 0), ("Measurement", None)]
    events = [m for m in pushed if isinstance(m, Event)]
    assert all(e.kind == EV_RANGE and e.channel == 1 for e in events)
    assert not any(m.fault_mask for m in pushed if isinstance(m, Measurement))
