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

from host.diagnosis import Diagnoser, Theory, load_system
from host.diagnosis.lags import observation_lags
from host.observers.config import load_observers
from tests.diagnosis.conftest import TEDUSAR

HEALTHY = ["on(jaguar)", "on(hokuyo)", "on(laser_alignment)", "in_band(jaguar)",
           "in_band(hokuyo)", "in_band(laser_alignment)", "link(board)", "running(jaguar_node)",
           "running(hokuyo_node)", "running(laser_alignment_node)", "running(imu_node)",
           "running(joy_node)", "running(jaguar_teleop_node)", "running(hector_mapping)",
           "running(laser_alignment_control)", "ok(/odom)", "ok(/scan)", "ok(/map)",
           "ok(/imu_data)", "ok(/cmd_vel)"]


def tedusar_diagnoser(theory: Theory) -> Diagnoser:
    lags = observation_lags(load_observers(TEDUSAR, load_system(TEDUSAR)).observers)
    assert lags["ok(/map)"] == 6.0 and lags["ok(/scan)"] == 0.5
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
    assert at(d, 43.0) == [frozenset()]  # 5.6 s after the scan came back: still held
    assert at(d, 43.5) == [frozenset({"hector_mapping"})]  # 6 s: now it is evidence
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
    assert at(d, 12.3) == [frozenset({"hector_mapping"})]  # silent a window later: evidence


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
    assert at(d, 38.9) == [frozenset()]  # still within the window after the scan's return
    assert at(d, 39.1) == [frozenset({"hector_mapping"})]  # a map still silent: evidence
