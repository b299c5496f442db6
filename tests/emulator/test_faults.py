"""Each injected fault, at its seam, does what it should, and the firmware reacts to it."""

from __future__ import annotations

import json

import pytest

from benchmarks._rigs.testhal import config_text
from emulator import faults as F
from emulator.model import EmulatorModelError, parse
from emulator.sim import Emulator
from firmware import config
from firmware.hal.storage import FileStorage
from protocol.constants import E_PROTECTED
from tests.emulator.conftest import TEDUSAR, tedusar


def ch(emu: Emulator, name: str) -> dict:  # type: ignore[type-arg]
    return next(c for c in emu.status()["channels"] if c["name"] == name)


def until(emu: Emulator, pred, limit_ms: int) -> int:  # type: ignore[no-untyped-def]
    start = emu.now
    while emu.now - start <= limit_ms:
        if pred():
            return emu.now - start
        emu.advance(10)
    return -1


def test_boot_powers_only_the_pc_and_every_device_runs_normally(emu: Emulator) -> None:
    s = emu.status()
    assert s["config_status"] == "ok"
    assert [c["state"] for c in s["channels"]] == ["on"] * 8 + ["off"] * 2
    assert all(c["live"] == [] for c in s["channels"])
    emu.advance(60000)  # a minute of noisy normal loads: no trip, no warning
    s = emu.status()
    assert all(c["sticky"] == [] for c in s["channels"]), s
    assert all(c["ready"] for c in s["channels"][:8])


def test_normal_inrush_of_every_device_does_not_trip() -> None:
    e = tedusar()
    e.advance(100)
    for i in range(8):
        e.board.switch(i, True)
    e.advance(1000)
    assert all(c["trips"] == 0 for c in e.status()["channels"])


def test_short_trips_retries_once_then_latches(emu: Emulator) -> None:
    emu.inject("hokuyo", "short", {})
    t = until(emu, lambda: ch(emu, "hokuyo")["state"] == "tripped", 500)
    assert 0 <= t <= 30
    assert until(emu, lambda: ch(emu, "hokuyo")["state"] == "latched", 2000) > 900
    assert emu.board.switch(3, True)[0] == 301  # E_LATCHED
    emu.clear("hokuyo")
    assert emu.board.clear(3)[0] == 0
    assert emu.board.switch(3, True)[0] == 0
    emu.advance(200)
    assert ch(emu, "hokuyo")["state"] == "on"


@pytest.mark.parametrize(("amps", "lo", "hi"), [(1.5, 2700, 3400), (2.0, 1000, 1300)])
def test_overcurrent_trips_by_i2t(emu: Emulator, amps: float, lo: int, hi: int) -> None:
    emu.inject(3, "overcurrent", {"amps": str(amps)})  # hokuyo is rated 1 A
    t = until(emu, lambda: ch(emu, "hokuyo")["state"] == "tripped", 5000)
    assert lo <= t <= hi
    assert ch(emu, "hokuyo")["live"] == ["overload"]


def test_open_load_warns(emu: Emulator) -> None:
    emu.inject("kinect", "open_load", {})
    t = until(emu, lambda: "open_load" in ch(emu, "kinect")["live"], 3000)
    assert 990 <= t <= 1100
    assert ch(emu, "kinect")["state"] == "on"
    emu.clear("kinect", "open_load")
    emu.advance(100)
    assert "open_load" not in ch(emu, "kinect")["live"]


def test_dropout_is_intermittent(emu: Emulator) -> None:
    emu.inject("router", "dropout", {"period_s": "0.5", "duty": "0.5"})
    seen = set()
    for _ in range(50):
        emu.advance(20)
        seen.add(ch(emu, "router")["current_ma"] == 0)
    assert seen == {True, False}
    assert ch(emu, "router")["state"] == "on"


def test_drift_ends_in_an_overload_trip(emu: Emulator) -> None:
    emu.inject("sensor_head", "drift", {"amps_per_s": "0.5"})  # rated 1.5 A
    t = until(emu, lambda: ch(emu, "sensor_head")["state"] == "tripped", 20000)
    assert 3000 < t < 12000
    assert ch(emu, "sensor_head")["live"] == ["overload"]


def test_hang_is_cured_by_a_power_cycle_unless_permanent(emu: Emulator) -> None:
    emu.inject("hokuyo", "hang", {"permanent": "false"})
    emu.advance(100)
    c = ch(emu, "hokuyo")
    assert not c["ready"] and c["state"] == "on" and 300 < c["current_ma"] < 500
    assert emu.board.power_cycle(3, 500)[0] == 0
    emu.advance(6000)
    assert ch(emu, "hokuyo")["ready"]
    emu.inject("hokuyo", "hang", {"permanent": "true"})
    emu.board.power_cycle(3, 500)
    emu.advance(6000)
    assert not ch(emu, "hokuyo")["ready"]


def test_stuck_on_switch_faults(emu: Emulator) -> None:
    emu.inject("kinect", "stuck_on", {})
    emu.board.switch(4, False)
    t = until(emu, lambda: ch(emu, "kinect")["state"] == "faulted", 1000)
    assert 190 <= t <= 230
    assert ch(emu, "kinect")["physical"] is True


def test_stuck_off_switch_faults(emu: Emulator) -> None:
    emu.inject("spare8", "stuck_off", {})
    emu.board.switch(8, True)
    assert until(emu, lambda: ch(emu, "spare8")["state"] == "faulted", 100) >= 0
    assert ch(emu, "spare8")["live"] == ["stuck_off"]


def test_sensor_faults_change_only_the_reading(emu: Emulator) -> None:
    emu.inject("jaguar", "sensor_offset", {"amps": "1"})
    emu.advance(20)
    c = ch(emu, "jaguar")
    assert c["current_ma"] - c["true_ma"] > 500
    emu.clear("jaguar")
    emu.inject("jaguar", "sensor_gain", {"factor": "0"})
    emu.advance(20)
    assert ch(emu, "jaguar")["current_ma"] == 0 and ch(emu, "jaguar")["true_ma"] > 1000
    emu.clear("jaguar")
    emu.inject("jaguar", "sensor_stuck", {})
    first = ch(emu, "jaguar")["current_ma"]
    emu.advance(200)
    assert ch(emu, "jaguar")["current_ma"] == first
    emu.clear("jaguar")
    emu.inject("thermal_camera", "sensor_noise", {"amps": "0.05"})
    readings = set()
    for _ in range(20):
        emu.advance(10)
        readings.add(ch(emu, "thermal_camera")["current_ma"])
    assert len(readings) > 10


def test_shallow_brownout_sheds_and_recovers(emu: Emulator) -> None:
    emu.inject("board", "brownout", {"volts": "20.0", "seconds": "3"})
    emu.advance(100)
    s = emu.status()
    assert "uv_shed" in s["flags"]
    assert [c["state"] for c in s["channels"][:8]] == ["off", "off", "on"] + ["off"] * 5
    emu.advance(6000)
    s = emu.status()
    assert s["flags"] == [] and s["boots"] == 1
    assert [c["state"] for c in s["channels"][:8]] == ["on"] * 8


def test_deep_brownout_resets_the_board() -> None:
    e = tedusar()
    e.advance(1000)
    e.inject("board", "brownout", {"volts": "5", "seconds": "0.5"})
    e.advance(100)
    assert not e.electronics.switches[2].closed
    e.advance(1000)
    s = e.status()
    assert s["reset_cause"] == "brownout" and s["boots"] == 2
    assert s["channels"][2]["state"] == "on"


def test_watchdog_resets_and_three_in_a_row_mean_safe_mode() -> None:
    e = tedusar()
    e.advance(500)
    e.board.switch(5, True)
    e.board.set_channel_config(5, {"powerup": True})
    e.board.save_config()
    for n in range(1, 4):
        e.inject("board", "wdt_reset", {})
        t = until(e, lambda n=n: len(e.boots) == n + 1, 5000)  # type: ignore[misc]
        assert 2000 <= t <= 2100
        e.advance(1000)
    s = e.status()
    assert s["reset_cause"] == "watchdog"
    assert s["config_status"] == "safe_mode" and "safe_mode" in s["flags"]
    assert s["channels"][2]["state"] == "on" and s["channels"][5]["state"] == "off"


def test_soft_reboot_keeps_saved_config(tmp_path) -> None:  # type: ignore[no-untyped-def]
    e = tedusar(storage=FileStorage(str(tmp_path)))
    e.advance(100)
    e.board.set_channel_config(3, {"powerup": True, "priority": 1})
    assert e.board.save_config() == 0
    e.board.request_reboot()
    e.advance(2000)
    s = e.status()
    assert s["reset_cause"] == "soft" and s["channels"][3]["state"] == "on"
    assert json.loads(config_text(FileStorage(str(tmp_path))))["channels"][3]["powerup"] is True


def test_corrupt_config_boots_the_factory_config(tmp_path) -> None:  # type: ignore[no-untyped-def]
    for name in config.SLOTS:
        (tmp_path / name).write_text('{"version": 1, "crc": "00000000"}')
    e = tedusar(storage=FileStorage(str(tmp_path)))
    e.advance(2000)
    s = e.status()
    assert s["config_status"] == "corrupt"
    # the configuration flashed with the board (board.json) keeps the pc on and protected
    assert [c["state"] for c in s["channels"]] == ["off", "off", "on"] + ["off"] * 7
    assert e.board.switch(2, False)[0] == E_PROTECTED


def test_link_faults_are_recorded_with_a_clear_hook(emu: Emulator) -> None:
    seen: list[dict] = []  # type: ignore[type-arg]
    emu.link_listeners.append(seen.append)
    emu.inject("board", "link_delay", {"ms": "250"})
    assert emu.link_faults == {"link_delay": {"ms": 250.0}}
    emu.clear("board")
    assert emu.link_faults == {} and seen[-1] == {}


@pytest.mark.parametrize(("channel", "fault", "params", "message"), [
    ("hokuyo", "melt", {}, "unknown fault"),
    ("hokuyo", "overcurrent", {}, "amps=... is required"),
    ("hokuyo", "overcurrent", {"amps": "lots"}, "must be a number"),
    ("hokuyo", "hang", {"forever": "1"}, "unknown parameter"),
    ("board", "short", {}, "channel fault"),
    ("hokuyo", "wdt_reset", {}, "board fault"),
    ("toaster", "short", {}, "no channel"),
    (12, "short", {}, "no channel"),
])
def test_bad_faults_are_refused_and_change_nothing(emu: Emulator, channel, fault, params,  # type: ignore[no-untyped-def]
                                                   message) -> None:
    before = emu.status()["channels"]
    with pytest.raises(F.FaultError, match=message):
        emu.inject(channel, fault, params)
    assert emu.active == {}
    emu.advance(10)
    assert [c["state"] for c in emu.status()["channels"]] == [c["state"] for c in before]


def test_model_errors_name_the_field() -> None:
    with pytest.raises(EmulatorModelError, match="channel 0: unknown field 'nominal'"):
        parse({"channels": [{"nominal": 3}]})
    with pytest.raises(EmulatorModelError, match="must be a non-negative integer"):
        parse({"channels": [{"nominal_ma": -3}]})
    assert TEDUSAR.is_dir()


def test_sensor_offset_on_the_pc_keeps_it_on_and_flags_it() -> None:
    """The finding of issue 12 and issue 25 item 8, on the emulated TEDUSAR board: a +4 A offset
    on the pc's current sensor made the I2t model switch the pc off for 1 s; now a protected
    channel is never switched off by it: the pc stays on and the board says ``overload``."""
    e = tedusar()
    e.advance(2000)
    e.inject("pc", "sensor_offset", {"amps": "4"})
    states = set()
    physical = set()
    for _ in range(120):
        e.advance(1000)
        states.add(e.status()["channels"][2]["state"])
        physical.add(e.status()["channels"][2]["physical"])
    pc = e.status()["channels"][2]
    assert states == {"on"} and physical == {True}
    assert "overload" in pc["live"] and "stuck_on" not in pc["sticky"]
