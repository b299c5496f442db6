"""Scenario files: parsing, errors that name the event, and repeatable runs on the emulator."""

from __future__ import annotations

import pytest

from emulator import scenario
from tests.emulator.conftest import TEDUSAR, tedusar


def states(emu, name):  # type: ignore[no-untyped-def]
    return next(c for c in emu.status()["channels"] if c["name"] == name)


def test_hokuyo_hang_is_cured_by_the_scheduled_power_cycle() -> None:
    sc = scenario.load(TEDUSAR / "scenarios" / "hokuyo-hang.yaml")
    emu = tedusar()
    scenario.schedule(emu, sc)
    emu.advance(7000)
    assert states(emu, "hokuyo")["ready"]
    emu.advance(2000)
    assert not states(emu, "hokuyo")["ready"] and states(emu, "hokuyo")["state"] == "on"
    emu.advance(sc.duration_ms - emu.now)
    assert states(emu, "hokuyo")["ready"] and emu.active == {}


def test_jaguar_stall_latches_after_three_retries_and_is_repeatable() -> None:
    sc = scenario.load(TEDUSAR / "scenarios" / "jaguar-stall.yaml")
    runs = []
    for _ in range(2):
        emu = tedusar()
        scenario.play(emu, sc)
        runs.append((states(emu, "jaguar"), list(emu.board.events.read(0, 1000)[0])))
    assert runs[0][0]["state"] == "latched" and runs[0][0]["trips"] == 4
    assert runs[0] == runs[1]


@pytest.mark.parametrize(("data", "message"), [
    ({"events": [{"at": 1, "inject": "melt", "channel": 1}]}, "event 0: unknown fault"),
    ({"events": [{"at": -1, "clear": "all"}]}, "event 0: 'at' must be"),
    ({"events": [{"at": 1, "inject": "short"}]}, "needs a channel"),
    ({"events": [{"at": 1}]}, "exactly one of"),
    ({"events": [{"at": 1, "switch": "explode", "channel": 1}]}, "switch: one of"),
    ([1, 2], "expected a mapping"),
])
def test_bad_scenarios_name_the_event(data, message) -> None:  # type: ignore[no-untyped-def]
    with pytest.raises(scenario.ScenarioError, match=message):
        scenario.parse(data, "x.yaml")


def test_unknown_channel_is_caught_when_scheduled() -> None:
    sc = scenario.parse({"events": [{"at": 1, "inject": "short", "channel": "toaster"}]})
    with pytest.raises(scenario.ScenarioError, match="no channel 'toaster'"):
        scenario.schedule(tedusar(), sc)
