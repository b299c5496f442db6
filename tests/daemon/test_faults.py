"""The emulator's remaining hardware faults, end to end through ``dxboard run --emulate``.

Each test injects one fault with ``dxboard inject`` into the running virtual TEDUSAR robot
and checks, from the daemon's JSON API and its journal, that the right component is
diagnosed and then either repaired and verified, or (where no repair by power or process can
help) quarantined after the limit with the rest of the robot untouched. The faults covered
here complement ``test_repairs.py`` (power-up, device shut-down, hang, overcurrent trip, link
loss, permanent hang):

- latch: a persistent short; the board retries once (``short_retries`` 1) and latches; once
  the short is gone the daemon's repair clears the latch and powers the device;
- open load: the device draws nothing while switched on (a cut cable); ``in_band`` turns
  false; a power cycle cannot cure it, so the device is quarantined after the limit;
- stuck-off: the switch does not follow its command; the board marks the channel faulted;
  no repair by power helps, so it is quarantined after the limit, nothing else touched;
- brown-out: the input sags below ``uv_shed_mv``; the board sheds its non-protected channels
  and restores them itself (hysteresis, then the power-up queue) when the voltage returns;
  the daemon diagnoses the shed devices, and the robot ends healthy with the PC never off.

One daemon serves the module, in order; each test starts healthy. The two quarantine tests
use different devices (quarantine is sticky) and run last.
"""

from __future__ import annotations

from collections.abc import Iterator
from typing import Any

import pytest

from host.events import describe
from host.journal import (
    ActionRecord,
    BoardEvent,
    DiagnosisRecord,
    Observation,
    PlanRecord,
)
from host.repair.executor import QUARANTINE_PLAN
from tests.daemon.runner import (
    RunningDaemon,
    bad_sets,
    healthy,
    healthy_robot,
    last_id,
)

HEAL_S = 90.0
QUARANTINE_S = 150.0


@pytest.fixture(scope="module")
def robot(tmp_path_factory: pytest.TempPathFactory) -> Iterator[RunningDaemon]:
    with healthy_robot(tmp_path_factory.mktemp("faults"), HEAL_S) as d:
        yield d


# --- helpers ------------------------------------------------------------------------------




def since(d: RunningDaemon, mark: int, kind: str) -> list[Any]:
    return [e.payload for e in d.journal(kind) if e.id > mark]


def actions(d: RunningDaemon, mark: int) -> list[ActionRecord]:
    return [p for p in since(d, mark, "action") if isinstance(p, ActionRecord)]


def finished(d: RunningDaemon, mark: int) -> list[tuple[str, tuple[str, ...], str]]:
    return [(r.action, tuple(r.args), str(r.state)) for r in actions(d, mark)
            if r.finished is not None]


def notes(d: RunningDaemon, mark: int) -> list[str]:
    """What the daemon said since ``mark``: its notes, how repairs ended, quarantines."""
    return [describe(e.payload) for e in d.journal(("note", "repair", "quarantine"))
            if e.id > mark]


def observed(d: RunningDaemon, mark: int, literal: str, value: bool | None) -> bool:
    return any(isinstance(p, Observation) and p.literal == literal and p.value is value
               for p in since(d, mark, "observation"))


def board_states(d: RunningDaemon, mark: int, channel: int) -> list[str]:
    """The channel's state changes the board reported since ``mark`` (``to`` of each event)."""
    return [str(p.detail.get("to")) for p in since(d, mark, "board_event")
            if isinstance(p, BoardEvent) and p.channel == channel and "to" in p.detail]


def named(d: RunningDaemon, mark: int, component: str) -> bool:
    return any(isinstance(p, DiagnosisRecord) and any(component in b for b in p.diagnoses)
               for p in since(d, mark, "diagnosis"))


def assert_journal_steps(d: RunningDaemon, mark: int, component: str, *,
                         repaired: bool) -> None:
    """The journal holds every step: the diagnosis, the plan, its actions and their results."""
    # the status can show a result before the journal's writer has committed it
    d.wait_journal(lambda: all_finished(d, mark), 30, "every started action's result")
    if repaired:
        d.wait_journal(lambda: any("repair ended: healthy" in t for t in notes(d, mark)), 30,
                       "the repair's end")
    assert named(d, mark, component), f"no diagnosis naming {component} in the journal"
    plans = [p for p in since(d, mark, "plan") if isinstance(p, PlanRecord)]
    assert plans, "no plan in the journal"
    acts = actions(d, mark)
    assert acts, "no action in the journal"
    plan_ids = {p.plan_id for p in plans}
    # every action belongs to a journaled plan, or is a quarantine's safe-state step
    assert all(a.plan_id in plan_ids or a.plan_id.startswith(f"{QUARANTINE_PLAN}:")
               for a in acts), "an action of no journaled plan"
    started = {a.action_id for a in acts if str(a.state) == "started"}
    results = {a.action_id for a in acts if a.finished is not None}
    assert started and started <= results, "an action started without a journaled result"
    if repaired:
        healthy_after = [p for p in since(d, mark, "diagnosis")
                         if isinstance(p, DiagnosisRecord)]
        assert healthy_after and healthy_after[-1].diagnoses in ((), ((),))


def all_finished(d: RunningDaemon, mark: int) -> bool:
    acts = actions(d, mark)
    started = {a.action_id for a in acts if str(a.state) == "started"}
    return started <= {a.action_id for a in acts if a.finished is not None}


def shed_by_board(d: RunningDaemon, mark: int) -> set[str]:
    """The devices the board itself switched off (shed) since ``mark``."""
    return {str(p.detail.get("name")) for p in since(d, mark, "board_event")
            if isinstance(p, BoardEvent) and p.event == "shed"}


def untouched(d: RunningDaemon, mark: int, component: str) -> None:
    """No power action on any device but ``component`` or one the board shed."""
    allowed = {component} | shed_by_board(d, mark)
    for r in actions(d, mark):
        if r.action in ("power_up", "shutdown", "power_cycle"):
            assert r.args[0] in allowed, f"{r.action}{r.args} touched another device"


# --- the tests ----------------------------------------------------------------------------


def test_a_persistent_short_latches_is_quarantined_unenergised_and_repaired_once_cleared(
        robot: RunningDaemon) -> None:
    d = robot
    d.wait_for(healthy, HEAL_S, "healthy")
    mark = last_id(d)
    d.inject("laser_alignment", "short")
    # the board trips, retries once after 1 s, trips again and latches the channel
    d.wait_journal(lambda: "latched" in board_states(d, mark, 1), 20, "the channel latched")
    states = board_states(d, mark, 1)
    assert states.index("tripped") < states.index("latched")
    assert "inrush" in states[states.index("tripped"):states.index("latched")]  # the retry
    d.wait_for(lambda s: any("laser_alignment" in b for b in bad_sets(s)), 15,
               "laser_alignment diagnosed")
    d.wait_journal(lambda: observed(d, mark, "tripped(laser_alignment)", True), 15,
                   "tripped(laser_alignment) = true journaled")
    # a short latched by the board is not energised again by the daemon: quarantined at once
    st = d.wait_for(lambda s: "laser_alignment" in s["quarantined"], 30, "quarantined")
    assert "short circuit" in st["quarantined"]["laser_alignment"]
    energised = [s for s in board_states(d, mark, 1) if s == "inrush"]
    assert len(energised) == 1  # the board's own retry, and nothing more
    power = [a for a in actions(d, mark) if a.action in ("power_up", "power_cycle")
             and a.finished is not None]
    assert all("not energised again" in a.detail for a in power), power  # refused, unsent
    d.inject("clear")  # the short is gone; a person checks the wiring and clears it
    assert d.operator("quarantine", "clear", "laser_alignment") == \
        "laser_alignment: quarantine cleared"
    d.wait_for(lambda s: healthy(s) and s["observations"].get("on(laser_alignment)") is True,
               HEAL_S, "laser_alignment powered again")
    d.caught_up()
    done = finished(d, mark)
    assert any(a in ("power_up", "power_cycle") and args == ("laser_alignment",)
               and state == "succeeded" for a, args, state in done), done
    # the daemon cleared the latch: the channel went from latched back through off to on
    states = board_states(d, mark, 1)
    assert states[-1] == "on" and "off" in states[states.index("latched"):]
    d.wait_journal(lambda: observed(d, mark, "tripped(laser_alignment)", False), 15,
                   "tripped(laser_alignment) = false journaled")
    assert_journal_steps(d, mark, "laser_alignment", repaired=True)
    # the 40 A short trips its own channel; nothing else is shed or touched
    untouched(d, mark, "laser_alignment")
    assert shed_by_board(d, mark) == set()


def test_a_brown_out_sheds_the_devices_and_the_robot_comes_back(robot: RunningDaemon) -> None:
    d = robot
    d.wait_for(healthy, HEAL_S, "healthy")
    mark = last_id(d)
    # 20.0 V: below uv_shed_mv (20.4 V), above uv_off_mv (19.8 V) and reset_mv
    d.inject("board", "brownout", "volts=20.0", "seconds=3")
    d.wait_journal(lambda: "off" in board_states(d, mark, 7) and "off" in
                   board_states(d, mark, 3), 15, "jaguar and hokuyo shed")
    d.wait_for(lambda s: any({"jaguar", "hokuyo"} & b for b in bad_sets(s)), 15,
               "the shed devices diagnosed")
    d.wait_for(lambda s: healthy(s) and all(s["observations"].get(f"on({x})") is True
                                            for x in ("jaguar", "hokuyo", "laser_alignment")),
               HEAL_S, "healthy again after the voltage returned")
    d.caught_up()
    # the board never switched off its protected channel, the PC
    assert "off" not in board_states(d, mark, 2)
    assert not any(r.args and r.args[0] == "pc" for r in actions(d, mark))
    shed = [p for p in since(d, mark, "board_event")
            if isinstance(p, BoardEvent) and p.event == "shed"]
    assert {p.channel for p in shed} >= {1, 3, 7}
    assert named(d, mark, "jaguar") or named(d, mark, "hokuyo")
    # the daemon left the channels to the board while it shed and restored them, and then
    # restarted what the outage broke: no step failed on a refusal of the board
    assert any(t.startswith("repairs wait: the board") for t in notes(d, mark)), notes(d, mark)
    assert all(state == "succeeded" for _, _, state in finished(d, mark)), finished(d, mark)


def test_an_open_load_is_diagnosed_and_quarantined(robot: RunningDaemon) -> None:
    d = robot
    d.wait_for(healthy, HEAL_S, "healthy")
    mark = last_id(d)
    d.inject("hokuyo", "open_load")  # a cut cable: switched on, draws nothing
    st = d.wait_for(lambda s: s["observations"].get("in_band(hokuyo)") is False, 15,
                    "in_band(hokuyo) false")
    assert st["observations"].get("on(hokuyo)") is True
    d.wait_for(lambda s: any("hokuyo" in b for b in bad_sets(s)), 15, "hokuyo diagnosed")
    # a power cycle does not reconnect a cut cable: after the limit, quarantine
    d.wait_journal(lambda: any(t.startswith("quarantined hokuyo") for t in notes(d, mark)),
                   QUARANTINE_S, "hokuyo quarantined")
    cycles = [r for r in actions(d, mark) if r.action in ("power_cycle", "power_up")
              and r.args == ("hokuyo",) and r.finished is not None]
    assert 1 <= len(cycles) <= 3
    assert_journal_steps(d, mark, "hokuyo", repaired=False)
    untouched(d, mark, "hokuyo")
    count = len(actions(d, mark))
    d.settled(4.0)
    assert len(actions(d, mark)) == count  # no loop of repairs
    st = d.status()
    assert st["observations"]["ok(/odom)"] is True  # the rest keeps running
    assert st["observations"]["ok(/imu_data)"] is True


def test_a_switch_stuck_off_is_quarantined_and_nothing_else_touched(
        robot: RunningDaemon) -> None:
    d = robot
    # hokuyo is quarantined by the previous test: wait for the rest to settle
    d.wait_for(lambda s: s["observations"].get("ok(/odom)") is True, HEAL_S, "the base up")
    mark = last_id(d)
    d.inject("laser_alignment", "stuck_off")
    d.wait_journal(lambda: "faulted" in board_states(d, mark, 1), 15, "the channel faulted")
    d.wait_for(lambda s: any("laser_alignment" in b for b in bad_sets(s)), 15,
               "laser_alignment diagnosed")
    d.wait_journal(lambda: observed(d, mark, "tripped(laser_alignment)", True), 15,
                   "tripped(laser_alignment) = true journaled")
    d.wait_journal(lambda: any(t.startswith("quarantined laser_alignment")
                                  for t in notes(d, mark)), QUARANTINE_S,
                   "laser_alignment quarantined")
    # the safe-state steps (the device off, its driver stopped) take a moment to finish
    d.wait_journal(lambda: all_finished(d, mark), 30, "the safe-state steps finished")
    assert_journal_steps(d, mark, "laser_alignment", repaired=False)
    untouched(d, mark, "laser_alignment")
    count = len(actions(d, mark))
    d.settled(4.0)
    assert len(actions(d, mark)) == count
    st = d.status()
    assert st["observations"]["ok(/odom)"] is True
    assert st["observations"]["on(jaguar)"] is True
