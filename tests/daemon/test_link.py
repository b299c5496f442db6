"""Link faults end to end through ``dxboard run --emulate``, as a user meets them.

- A frozen link (``dxboard inject CONTROL board link_freeze seconds=5``) is a lost link: the
  page's ``board_link_up`` turns false within the client's silence limit, comes back after the
  freeze, and the board's literals (``tripped(hokuyo)`` among them) are known again at once —
  with no repair of a healthy device and no traceback in the daemon's log.
- A brown-out below the reset voltage holds the board in reset for 3 s: the link is down for the
  whole hold (the emulated board still answers on the network, but its clock stands still),
  nothing is sent to it meanwhile, and the reboot shows as what it is: a ``rebooted`` board event
  with reset cause ``brownout``, then the new boot's state.

One daemon serves the module; each test starts from a healthy robot.
"""

from __future__ import annotations

import time
from collections.abc import Iterator

import pytest

from host.events import LinkChange
from host.journal import ActionRecord, BoardEvent, Note
from tests.daemon.runner import RunningDaemon, healthy, healthy_robot, last_id

HEAL_S = 90.0
BOARD_POWER = ("power_up", "power_cycle", "shutdown")


@pytest.fixture(scope="module")
def robot(tmp_path_factory: pytest.TempPathFactory) -> Iterator[RunningDaemon]:
    with healthy_robot(tmp_path_factory.mktemp("link"), HEAL_S) as d:
        yield d


def since(d: RunningDaemon, mark: int) -> list[tuple[int, object]]:
    return [(e.id, e.payload) for e in d.journal() if e.id > mark]


def tracebacks(d: RunningDaemon) -> list[str]:
    text = d.err_path.read_text(errors="replace")
    return [block[:400] for block in text.split("Traceback")[1:]]


def test_a_frozen_link_is_lost_and_the_literals_come_back(robot: RunningDaemon) -> None:
    d = robot
    mark = last_id(d)
    assert d.status()["observations"]["tripped(hokuyo)"] is False
    d.inject("board", "link_freeze", "seconds=5")
    t0 = time.monotonic()
    down = d.wait_for(lambda s: not s["board_link_up"], 10.0, "the link judged lost")
    assert time.monotonic() - t0 < 5.0  # within the freeze, not after it
    assert down["observations"].get("tripped(hokuyo)") is None  # unknown while lost
    st = d.wait_for(lambda s: s["board_link_up"]
                    and s["observations"].get("tripped(hokuyo)") is False, 30.0,
                    "the link back and tripped(hokuyo) known again")
    assert st["observations"]["on(hokuyo)"] is True
    d.wait_for(healthy, 30.0, "healthy again")

    def journaled() -> list[LinkChange]:  # the journal may lag the page on a busy machine
        return [p for _, p in since(d, mark) if isinstance(p, LinkChange)]

    d.wait_journal(lambda: [lc.up for lc in journaled()][:2] == [False, True], 30.0,
                   "the link's loss and return journaled")
    entries = since(d, mark)
    links = journaled()
    assert "nothing from the board for" in links[0].reason
    power = [p for _, p in entries if isinstance(p, ActionRecord) and p.action in BOARD_POWER]
    assert power == [], f"healthy devices were switched: {power}"
    assert tracebacks(d) == []


def test_a_board_held_in_reset_is_down_and_its_reboot_is_seen(robot: RunningDaemon) -> None:
    d = robot
    mark = last_id(d)
    d.inject("board", "brownout", "volts=5", "seconds=3")  # below reset_mv: held in reset
    d.wait_for(lambda s: not s["board_link_up"], 10.0, "the link down in reset")
    d.wait_for(lambda s: s["board_link_up"], 30.0, "the link back after the reboot")
    d.wait_for(healthy, HEAL_S, "healthy again")
    entries = since(d, mark)
    down_at = next(i for i, p in entries if isinstance(p, LinkChange) and not p.up)
    up_at = next(i for i, p in entries if isinstance(p, LinkChange) and p.up and i > down_at)
    # down once for the whole hold: the board in reset never looked alive
    assert [p.up for _, p in entries if isinstance(p, LinkChange)][:2] == [False, True]
    reboots = [p for _, p in entries if isinstance(p, BoardEvent) and p.event == "rebooted"]
    assert len(reboots) == 1 and reboots[0].detail["reset_cause"] == "brownout"
    assert reboots[0].detail["how"] == "boot id"
    assert any(isinstance(p, Note) and "rebooted (reset cause brownout)" in p.text
               for _, p in entries)
    fresh = [i for i, p in entries if isinstance(p, BoardEvent) and p.event == "link_up"]
    assert fresh and down_at < fresh[0] <= up_at  # the new boot's state, before it is up
    sent = [p for i, p in entries if down_at < i < up_at and isinstance(p, ActionRecord)
            and p.action in BOARD_POWER]
    assert sent == [], f"switched while the board was in reset: {sent}"
    assert tracebacks(d) == []


def test_reboots_in_a_row_quarantine_nothing(robot: RunningDaemon) -> None:
    """Issue 11, item 5: board reboots one after another (here four watchdog resets, each as
    soon as the robot is healthy again) used to end with the base, the lidar and the leveling
    mount quarantined: every bring-up after a reboot counted as a repair that did not hold."""
    d = robot
    mark = last_id(d)
    for k in range(4):
        before = last_id(d)
        d.inject("board", "wdt_reset")
        d.wait_journal(lambda b=before: any(isinstance(p, BoardEvent) and p.event == "rebooted"
                                            for _, p in since(d, b)), 30.0, f"reboot {k + 1}")
        d.wait_for(healthy, HEAL_S, f"healthy after reboot {k + 1}")
    assert d.status()["quarantined"] == {}
    assert not any(isinstance(p, Note) and p.text.startswith("quarantined")
                   for _, p in since(d, mark))
