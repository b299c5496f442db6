"""hector_mapping ranked first after a lidar fault (issue 11 item 4): why, and the fix.

Reproduced on the emulated TEDUSAR robot (``dxboard run models/tedusar --emulate``, then
``dxboard inject ... hokuyo hang``): the daemon power-cycled the lidar and restarted its
driver; ``ok(/scan)`` came back at once (its frequency observer's window is 0.5 s) while
``~ok(/map)`` stayed for seconds (hector_mapping publishes every 2 s and its observer judges
the rate over a 6 s window that still held the outage). For those seconds the observations
say "hector_mapping runs, its input is fine, its output is not": {hector_mapping} was the
*only* minimal diagnosis, so no ranking could put anything else first, and the daemon
restarted a healthy node. The times below are that run's (the journal's, in seconds).

The fix: an observation that judges a window of time (``lags``: the observer's window) says
nothing about a node while an input the node needs changed within that window; the diagnoser
holds it as unknown until the window has passed (``DiagnosisResult.held`` names it).
"""

from __future__ import annotations

import pytest

from host.diagnosis import Diagnoser, Theory, load_system
from host.diagnosis.lags import observation_lags
from host.diagnosis.observations import Observation
from host.observers import FrequencyObserver
from host.observers.config import load_observers
from host.observers.payload import TopicMessage
from tests.diagnosis.conftest import TEDUSAR

HEALTHY = ["on(jaguar)", "on(hokuyo)", "on(laser_alignment)", "in_band(jaguar)",
           "in_band(hokuyo)", "in_band(laser_alignment)", "link(board)", "running(jaguar_node)",
           "running(hokuyo_node)", "running(laser_alignment_node)", "running(imu_node)",
           "running(joy_node)", "running(jaguar_teleop_node)", "running(hector_mapping)",
           "running(laser_alignment_control)", "ok(/odom)", "ok(/scan)", "ok(/map)",
           "ok(/imu_data)", "ok(/cmd_vel)"]


def tedusar_diagnoser(theory: Theory) -> Diagnoser:
    lags = observation_lags(load_observers(TEDUSAR, load_system(TEDUSAR)).observers)
    # its window and one interval at the slowest rate still ok (the map: 0.2 Hz, 5 s)
    assert lags["ok(/map)"] == 11.0 and lags["ok(/scan)"] == pytest.approx(0.5 + 1 / 30)
    d = Diagnoser(theory, lags=lags)
    for atom in HEALTHY:
        d.observe(atom, now=0.0)
    return d


def at(d: Diagnoser, now: float, *literals: str) -> list[frozenset[str]]:
    for lit in literals:
        d.observe(lit, now=now)
    d.expire(now)
    return d.diagnose().bad_sets()


def test_the_lidar_recovers_before_the_maps_observer_does(tedusar: Theory) -> None:
    d = tedusar_diagnoser(tedusar)
    assert at(d, 10.0) == [frozenset()]
    # the lidar hangs: its driver's topic stops first, the map 5 s later
    assert sorted(at(d, 29.04, "~ok(/scan)"), key=sorted) == [
        frozenset({"hokuyo"}), frozenset({"hokuyo_node"})]
    assert sorted(at(d, 34.28, "~ok(/map)"), key=sorted) == [
        frozenset({"hokuyo"}), frozenset({"hokuyo_node"})]
    # repaired: the scan is back; the map's observer still averages over the outage
    result_bad = at(d, 37.41, "ok(/scan)")
    assert result_bad == [frozenset()]  # was [{hector_mapping}]: a false repair followed
    assert d.diagnose().held == ("ok(/map)",)
    assert at(d, 39.9, "ok(/map)") == [frozenset()]  # the map came back in time
    assert d.diagnose().held == ()  # a map seen flowing after the change: evidence at once


def test_a_map_that_stays_silent_is_diagnosed_once_its_window_has_passed(
    tedusar: Theory,
) -> None:
    d = tedusar_diagnoser(tedusar)
    at(d, 29.04, "~ok(/scan)")
    at(d, 34.28, "~ok(/map)")
    assert at(d, 37.41, "ok(/scan)") == [frozenset()]
    assert at(d, 48.0) == [frozenset()]  # 10.6 s after the scan came back: still held
    assert at(d, 48.5) == [frozenset({"hector_mapping"})]  # 11 s: now it is evidence
    assert d.diagnose().held == ()


def test_without_lags_nothing_is_held(tedusar: Theory) -> None:
    d = Diagnoser(tedusar)
    for atom in HEALTHY:
        d.observe(atom, now=0.0)
    at(d, 29.04, "~ok(/scan)")
    at(d, 34.28, "~ok(/map)")
    assert at(d, 37.41, "ok(/scan)") == [frozenset({"hector_mapping"})]


def test_a_map_silence_noticed_just_after_the_scan_came_back_is_held_too(
    tedusar: Theory,
) -> None:
    # the fault campaign (seed 1, --quick, brownout): the board rebooted, ~ok(/scan) at 0.57 s;
    # the lidar's repair brought ok(/scan) back at 6.26 s, and only then, at 6.40 s, did the
    # map's observer notice the silence: a judgement of a window that held the outage, which
    # made {hector_mapping} the only diagnosis and the daemon restarted a healthy node
    d = tedusar_diagnoser(tedusar)
    at(d, 0.57, "~ok(/scan)")
    assert at(d, 6.26, "ok(/scan)") == [frozenset()]
    assert at(d, 6.40, "~ok(/map)") == [frozenset()]  # was [{hector_mapping}]
    assert d.diagnose().held == ("ok(/map)",)
    assert at(d, 17.3) == [frozenset({"hector_mapping"})]  # silent a lag later: evidence


def test_a_map_judged_silent_after_the_lidar_came_back_is_held(tedusar: Theory) -> None:
    """Issue 18 item 1, from the loop benchmark's journal: a faster lidar repair brings
    ``ok(/scan)`` back *before* the map's observer (6 s window, silence of 3 periods) has
    even noticed the outage; its ``~ok(/map)``, established after the scan's change, still
    judges a window that holds the outage and named hector_mapping, which was restarted."""
    d = tedusar_diagnoser(tedusar)
    at(d, 29.04, "~ok(/scan)")
    assert at(d, 33.0, "ok(/scan)") == [frozenset()]  # repaired within 4 s
    assert at(d, 34.28, "~ok(/map)") == [frozenset()]  # was [{hector_mapping}]
    assert d.diagnose().held == ("ok(/map)",)
    assert at(d, 43.9) == [frozenset()]  # still within the lag after the scan's return
    assert at(d, 44.1) == [frozenset({"hector_mapping"})]  # a map still silent: evidence


def test_a_map_late_after_the_scans_return_is_held_until_its_next_message(
        tedusar: Theory) -> None:
    """The learned-vs-written benchmark (round 5): hector_mapping was restarted because
    ``~ok(/map)`` stood 6 s after ``/scan`` came back. A map's verdict changes only when a map
    arrives (or its silence limit passes): here the first map after the scan's return comes
    5 s late (a busy machine), the map is judged silent meanwhile, and only the map after it
    judges a window that no longer holds the outage, one interval past the window. Replayed
    through the real observer: its verdicts, at their times, into the diagnoser."""
    obs = FrequencyObserver("/map", rate=0.5, tolerance=0.3, window=6.0, silence=3)
    verdicts: list[tuple[float, bool]] = []
    maps = [*range(0, 19, 2), 24.0, 26.0, 28.0]  # every 2 s; the scan stops at 18.5, back
    for t in maps:                                # at 19; hector's next map 5 s after that
        ups = []
        while (due := obs.next_deadline()) is not None and due < t:  # the hub's ticks
            ups += obs.tick(due)
        ups += obs.feed(TopicMessage(t, "/map"), t)
        verdicts += [(round(u.time, 2), u.literal.positive) for u in ups
                     if isinstance(u, Observation)]
    # the map silent at 24 (6 s after the last one), its window ok again with the map at 26
    assert [v for t, v in verdicts if 24.0 <= t <= 26.0] == [False, False, True], verdicts
    d = tedusar_diagnoser(tedusar)
    assert at(d, 18.6, "~ok(/scan)") == [frozenset({"hokuyo"}), frozenset({"hokuyo_node"})]
    assert at(d, 19.0, "ok(/scan)") == [frozenset()]
    assert at(d, 24.0, "~ok(/map)") == [frozenset()]
    # 6.1 s after the scan's return: the window alone is over, the verdict still stale
    assert at(d, 25.1) == [frozenset()], "held for the window only: hector blamed"
    assert d.diagnose().held == ("ok(/map)",)
    assert at(d, 26.0, "ok(/map)") == [frozenset()]  # the map's next message: it is fine
    assert d.diagnose().held == ()
