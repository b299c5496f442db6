"""``/board_stream``: every item the hardware observer is fed, as a standard ROS 2 message and back.

Each kind of board item (a reading, an event, a state with its channels, the link going down
and up, a reboot) goes through real CDR bytes (rclpy's serialisation of a
``diagnostic_msgs/DiagnosticArray``) and decodes to the same value, stamped with its own
time; a hardware observer fed from such messages on ``ClockedObservers`` (as ``dxboard
replay`` feeds it) sees a trip, and its link goes down by its own deadline when the stream
stops. Bytes that are not a board item decode to nothing.
"""

from __future__ import annotations

import dataclasses

import pytest
from diagnostic_msgs.msg import DiagnosticArray
from rclpy.serialization import serialize_message

from host.board.types import BoardInfo, LinkDown, LinkUp, Rebooted
from host.observers import Device, HardwareObserver, Retraction, Update
from host.observers.silence import JITTER_S
from host.observers.sources.ros2_message import RosMessage
from host.ros import boardstream
from host.ros.offline import ClockedObservers, Reorder, bag_observers
from protocol.constants import EV_TRIP, ST_ON, ST_TRIPPED
from tests.observers.test_hardware import event, reading, state

INFO = BoardInfo("tcp://127.0.0.1:1", "tcp", 1, "b-1", "0.9", 10, 3, 7, 1, 0,
                 frozenset({"hmac", "events"}))


def wire(item: object, arrival: float | None = None) -> RosMessage:
    """The item as the bytes a recorder gets, arriving at ``arrival`` (default its stamp)."""
    payload = bytes(serialize_message(boardstream.message(item)))  # type: ignore[arg-type]
    t = item.host_time if arrival is None else arrival  # type: ignore[attr-defined]
    return RosMessage(t, boardstream.TOPIC, payload, boardstream.TYPE)


def test_every_kind_of_board_item_goes_over_the_wire_and_back() -> None:
    items = [reading(17, {3: 512, 7: 2400}, 1700000000.125, faults=1 << 3),
             event(EV_TRIP, 3, ST_ON, ST_TRIPPED),
             state({3: (True, ST_ON, 0), 7: (False, ST_TRIPPED, 1)}),
             LinkDown(1700000001.5, "no reading for 0.3 s"),
             LinkUp(1700000002.25, 0.75, INFO),
             Rebooted(1700000003.0, 7, 8, 1, "boot id")]
    for item in items:
        msg = wire(item, arrival=item.host_time + 0.01)
        assert boardstream.decode(msg) == item
        assert abs(boardstream.when(msg) - item.host_time) < 1e-6  # its stamp, not arrival
    array = boardstream.message(items[0])
    assert isinstance(array, DiagnosticArray)  # a plain ROS tool reads it as what it is
    assert array.status[0].message == "reading"
    assert {kv.key: kv.value for kv in array.status[0].values}["currents_ma"].startswith("0,0,")


def test_what_is_not_a_board_item_decodes_to_nothing() -> None:
    other = DiagnosticArray()
    for payload in (b"\x00\x01\x00\x00garbage", bytes(serialize_message(other))):
        assert boardstream.decode(RosMessage(1.0, boardstream.TOPIC, payload,
                                             boardstream.TYPE)) is None


def test_a_hardware_observer_on_the_bags_clock_sees_a_trip_and_the_link_go() -> None:
    hw = HardwareObserver({"hokuyo": Device("hokuyo", 3, (0.2, 1.2))}, link_timeout=0.25)
    out: list[tuple[str, float]] = []

    def sink(updates: list[Update], t: float) -> None:
        out.extend((u.atom if isinstance(u, Retraction) else str(u.literal), t)
                   for u in updates)

    clocked = ClockedObservers([hw], sink)
    assert boardstream.TOPIC in clocked.topics
    clocked.start(100.0)
    waiting = Reorder(0.5)
    # healthy readings, then the trip (the event, and the switch off with a live fault);
    # each reading arrives 30 ms after its stamp
    stamps = [100.0 + i * 0.01 for i in range(10)]
    msgs = [wire(reading(i, {3: 500} if i < 5 else {}, t, faults=0 if i < 5 else 1 << 3),
                 arrival=t + 0.03) for i, t in enumerate(stamps)]
    trip = dataclasses.replace(event(EV_TRIP, 3, ST_ON, ST_TRIPPED), host_time=100.045)
    msgs.insert(6, wire(trip, arrival=100.2))  # the board's claim, late: a reorder puts it back
    for m in msgs:
        waiting.push(m)
        for due in waiting.due(m.time):
            clocked.feed(due)
    for due in waiting.drain():
        clocked.feed(due)
    clocked.advance(101.0)  # no reading after 100.09: the link is gone 0.25 s later,
    # confirmed by an on-time tick JITTER_S after that (host/observers/silence.py)
    said: dict[str, float] = {}
    for atom, t in out:
        said.setdefault(atom, t)  # when each was first said
    ns = pytest.approx  # a stamp is whole nanoseconds
    assert said["on(hokuyo)"] == ns(100.02) and said["in_band(hokuyo)"] == ns(100.02)
    assert said["tripped(hokuyo)"] == ns(stamps[7])  # three readings agree: at their stamps
    gone = stamps[-1] + 0.25 + JITTER_S
    assert said["~link(board)"] == ns(gone)
    assert [t for a, t in out if a == "on(hokuyo)"][-1] == ns(gone)  # unknown
    assert [a for a, _ in out].index("tripped(hokuyo)") < [a for a, _ in out].index(
        "~link(board)")


def test_a_bags_hardware_observer_takes_a_gap_in_the_daemons_stream_for_its_scheduling() -> None:
    """The recorder sees the board through the daemon: a gap in ``/board_stream`` shorter than
    the daemon's own cap (``link_timeout + link_slack``) may be the daemon's loop held up, which
    the daemon's observer excuses and a recorder cannot tell; found under a CPU hog, where the
    recorder called the link lost for a 0.3 s gap the daemon never saw as one, and blamed the
    tripped device twice. A stream that stops is still a lost link, at the cap."""
    robot = HardwareObserver({"hokuyo": Device("hokuyo", 3, (0.2, 1.2))}, link_timeout=0.25,
                             link_slack=0.75)
    [hw] = bag_observers([robot])
    assert isinstance(hw, HardwareObserver) and hw is not robot  # the robot's stays as it is
    assert (robot.link_timeout, robot.link_slack) == (0.25, 0.75)
    out: list[tuple[str, float]] = []

    def sink(updates: list[Update], t: float) -> None:
        out.extend((u.atom if isinstance(u, Retraction) else str(u.literal), t)
                   for u in updates)

    clocked = ClockedObservers([hw], sink)
    clocked.start(100.0)
    # readings at 100 Hz, a 0.4 s gap in the daemon's feed (its loop held up), then more
    stamps = [100.0 + i * 0.01 for i in range(20)] + [100.59 + i * 0.01 for i in range(20)]
    for i, t in enumerate(stamps):
        clocked.advance(t)  # other topics' arrivals drive the clock through the gap
        clocked.feed(wire(reading(i, {3: 500}, t)))
    assert ("~link(board)", pytest.approx(100.19 + 0.25 + JITTER_S)) not in out
    assert all(a != "~link(board)" for a, _ in out), out
    clocked.advance(102.0)  # the stream stops: the link is gone at the cap
    gone = [t for a, t in out if a == "~link(board)"]
    assert gone == [pytest.approx(stamps[-1] + 1.0)], out
