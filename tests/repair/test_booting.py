"""``host.repair.booting``: what is still booting, and which devices came back by themselves
(the rules behind issue 25, item 7's brown-out and restart findings; end to end in
``tests/daemon/test_false_repairs.py`` and ``test_restart_settle.py``)."""

from __future__ import annotations

from host.diagnosis.observations import Observation, ObservationSet
from host.repair.booting import booting, came_back, describe

SETTLE = {"hokuyo": 2.0, "hokuyo_node": 1.0, "jaguar": 1.5}
COMPS = [("hokuyo", False), ("hokuyo_node", True), ("jaguar", False)]


def obs(*pairs: tuple[str, float]) -> ObservationSet:
    s = ObservationSet()
    for text, t in pairs:
        s.add(Observation.parse(text, t))
    return s


def test_up_for_less_than_the_settle_time_is_booting() -> None:
    s = obs(("on(hokuyo)", 10.0), ("running(hokuyo_node)", 11.0), ("on(jaguar)", 5.0))
    left = booting(s, SETTLE, COMPS, 11.5)
    assert left == {"hokuyo": 0.5, "hokuyo_node": 0.5}  # jaguar has settled long ago
    assert describe(left) == "hokuyo, hokuyo_node just came up: booting (up to 0.5 s more)"
    assert booting(s, SETTLE, COMPS, 12.0) == {}


def test_on_a_busy_machine_a_node_boots_longer_and_a_device_does_not() -> None:
    """Busy twice over, a node's settle time is twice as long (its process starts twice as
    slowly, as the executor stretches a start step's); a device boots in its own time."""
    s = obs(("on(hokuyo)", 10.0), ("running(hokuyo_node)", 10.0))
    assert booting(s, SETTLE, COMPS, 11.5) == {"hokuyo": 0.5}
    assert booting(s, SETTLE, COMPS, 11.5, stretch=2.0) == {"hokuyo": 0.5, "hokuyo_node": 0.5}
    assert booting(s, SETTLE, COMPS, 11.5, stretch=0.5) == {"hokuyo": 0.5}  # never shorter


def test_off_or_unknown_is_not_booting() -> None:
    s = obs(("~on(hokuyo)", 10.0))
    assert booting(s, SETTLE, COMPS, 10.5) == {}


def test_a_device_on_without_a_switch_on_of_ours_came_back() -> None:
    s = obs(("on(hokuyo)", 10.0), ("on(jaguar)", 10.0))
    devices = [("hokuyo", 3), ("jaguar", 7)]
    ours = [(9.8, 7, True)]  # this host switched the base on just before it came on
    assert came_back(s, SETTLE, devices, ours, 13.0) == {"hokuyo"}
    assert came_back(s, SETTLE, devices, [], 13.0) == {"hokuyo", "jaguar"}
    assert came_back(s, SETTLE, devices, [], 33.0) == set()  # long since booted: forgotten
