"""The daemon's Prometheus metrics (host/fleet): values from the status and the event stream,
served by the web server, and a real scrape of a running daemon checked by ``promtool``."""

from __future__ import annotations

import asyncio
import sqlite3
import subprocess
import sys
import time
import urllib.request
from collections.abc import Iterator
from pathlib import Path

import aiohttp
import pytest

from benchmarks._rigs.robots import lite_model
from host.events import (
    ActionRecord,
    ActionState,
    ChannelReading,
    ChannelSample,
    DiagnosisRecord,
    Event,
    Observation,
    RunStarted,
    Stamped,
)
from host.fleet.metrics import FleetMetrics, LagProbe
from host.journal import Journal
from host.web import MemoryStatusSource, WebServer
from host.web.status import ChannelView, Status
from tests.daemon.runner import RunningDaemon
from tests.fleet.tools import promtool, samples
from tests.wait import wait_until, wait_until_async
from tests.web.demo import demo_status

R = 'robot="rover-1",site="lab"'


def feed(metrics: FleetMetrics, *events: tuple[float, Event]) -> None:
    for mono, e in events:
        metrics.events(Stamped(1000.0 + mono, mono, e))


def channels(*on: bool, input_mv: int = 22200) -> ChannelSample:
    return ChannelSample(tuple(ChannelReading(i, f"ch{i}", o, "on" if o else "off", 100.0)
                               for i, o in enumerate(on)), input_mv)


async def test_the_web_server_serves_the_fleet_metrics(tmp_path: Path) -> None:
    source = MemoryStatusSource(demo_status(time.time()))
    source.update(quarantined={"hokuyo": "3 attempts failed"}, held={"imu": "new cable"})
    with Journal(tmp_path / "j.sqlite") as journal:
        metrics = FleetMetrics(source, robot="rover-1", site="lab", journal=journal,
                               components=["jaguar", "jaguar_node", "hokuyo", "imu", "kinect"],
                               protected=[2], lag=LagProbe())
        web = WebServer(source, journal.reader, metrics=metrics.render)
        await web.start("127.0.0.1", 0)
        try:
            async with aiohttp.ClientSession() as s, \
                    s.get(f"http://127.0.0.1:{web.port}/metrics") as resp:
                assert resp.status == 200
                assert resp.headers["Content-Type"].startswith("text/plain; version=0.0.4")
                text = await resp.text()
        finally:
            await web.close()
    code, out = promtool("check", "metrics", stdin=text)
    assert code == 0, out
    got = samples(text)
    assert got[f'dxboard_channel_current_amperes{{channel="7",name="jaguar",{R}}}'] == 7.4
    assert got[f'dxboard_channel_state{{channel="6",name="thermal_camera",{R},state="tripped"}}'] \
        == 1
    assert got[f'dxboard_channel_protected{{channel="2",name="pc",{R}}}'] == 1
    assert got[f'dxboard_channel_protected{{channel="3",name="hokuyo",{R}}}'] == 0
    # the best diagnosis is {jaguar_node}; the second also names jaguar_teleop_node
    assert got[f'dxboard_component_abnormal{{component="jaguar_node",{R}}}'] == 1
    assert got[f'dxboard_component_health{{component="jaguar_node",{R}}}'] == 2
    assert got[f'dxboard_component_health{{component="jaguar_teleop_node",{R}}}'] == 1
    assert got[f'dxboard_component_health{{component="jaguar",{R}}}'] == 0
    assert got[f'dxboard_component_health{{component="hokuyo",{R}}}'] == 3
    assert got[f'dxboard_component_quarantined{{component="hokuyo",{R}}}'] == 1
    assert got[f'dxboard_component_quarantined{{component="kinect",{R}}}'] == 0
    assert got[f'dxboard_component_held{{component="imu",{R}}}'] == 1
    assert got[f'dxboard_repairs_total{{outcome="failed",{R}}}'] == 1
    assert got[f"dxboard_diagnosis_duration_seconds_count{{{R}}}"] == 12
    assert got[f"dxboard_board_link_up{{{R}}}"] == 1
    assert got[f"dxboard_journal_backlog_entries{{{R}}}"] == 0
    assert got[f"dxboard_journal_write_failures_total{{{R}}}"] == 0
    assert got[f"dxboard_journal_bytes{{{R}}}"] > 0
    assert got[f"dxboard_daemon_lag_seconds{{{R}}}"] >= 0
    assert not any(k.endswith("_created") for k in got)  # no second series per counter


async def test_without_metrics_the_server_says_so() -> None:
    web = WebServer(MemoryStatusSource())
    await web.start("127.0.0.1", 0)
    try:
        async with aiohttp.ClientSession() as s, \
                s.get(f"http://127.0.0.1:{web.port}/metrics") as resp:
            assert resp.status == 404
            assert "no metrics" in await resp.text()
    finally:
        await web.close()


def test_label_values_are_escaped() -> None:
    source = MemoryStatusSource(Status(
        channels=(ChannelView(0, 'odd "name"\\x\n', True, "on", 1500.0),)))
    text = FleetMetrics(source, robot="r").render().decode()
    assert 'name="odd \\"name\\"\\\\x\\n"' in text
    assert promtool("check", "metrics", stdin=text)[0] == 0


def test_times_to_diagnosis_and_to_healthy_come_from_the_stream() -> None:
    metrics = FleetMetrics(MemoryStatusSource(), robot="rover-1", site="lab")
    feed(metrics,
         (0.0, RunStarted("r1", "lite", healthy={"in_band(hokuyo)": True})),
         (1.0, DiagnosisRecord(((),))),
         (2.0, Observation("in_band(hokuyo)", True)),  # healthy value: no fault
         (10.0, Observation("in_band(hokuyo)", False)),
         (10.4, Observation("in_band(hokuyo)", None)),  # the first departure counts
         (10.25, DiagnosisRecord((("hokuyo",),))),
         (12.0, DiagnosisRecord((("hokuyo",), ("board",)))),  # still bad: no new sample
         (16.0, DiagnosisRecord(((),))))
    got = samples(metrics.render().decode())
    assert got[f"dxboard_time_to_diagnosis_seconds_count{{{R}}}"] == 1
    assert got[f"dxboard_time_to_diagnosis_seconds_sum{{{R}}}"] == pytest.approx(0.25)
    assert got[f'dxboard_time_to_diagnosis_seconds_bucket{{le="0.25",{R}}}'] == 1
    assert got[f"dxboard_time_to_healthy_seconds_count{{{R}}}"] == 1
    assert got[f"dxboard_time_to_healthy_seconds_sum{{{R}}}"] == pytest.approx(6.0)


def test_repair_actions_and_channel_switches_are_counted() -> None:
    metrics = FleetMetrics(MemoryStatusSource(), robot="rover-1", site="lab")
    feed(metrics,
         (0.0, channels(True, False)),
         (0.1, ActionRecord("a1", "power_cycle", ("hokuyo",), ActionState.STARTED, 0.1)),
         (0.2, channels(True, True)),
         (0.3, ActionRecord("a1", "power_cycle", ("hokuyo",), ActionState.SUCCEEDED, 0.1, 0.3)),
         (0.4, ActionRecord("a2", "power_cycle", ("hokuyo",), ActionState.STARTED, 0.4)),
         (0.5, ActionRecord("a2", "power_cycle", ("hokuyo",), ActionState.TIMEOUT, 0.4, 0.5)),
         (0.6, channels(False, True, input_mv=19500)))
    got = samples(metrics.render().decode())
    a = f'action="power_cycle",component="hokuyo",{R}'
    assert got[f"dxboard_repair_actions_started_total{{{a}}}"] == 2
    assert got[f"dxboard_repair_actions_succeeded_total{{{a}}}"] == 1
    assert got[f"dxboard_repair_actions_failed_total{{{a}}}"] == 1
    assert got[f'dxboard_channel_switches_total{{channel="0",name="ch0",{R}}}'] == 1
    assert got[f'dxboard_channel_switches_total{{channel="1",name="ch1",{R}}}'] == 1
    assert got[f"dxboard_board_input_voltage_volts{{{R}}}"] == 19.5


@pytest.fixture
def daemon(tmp_path: Path) -> Iterator[RunningDaemon]:
    d = RunningDaemon(tmp_path, lite_model(tmp_path),
                      ("--middleware", "zenoh", "--robot", "rover-1", "--site", "lab"))
    try:
        yield d
    finally:
        d.close()


def test_a_running_daemons_scrape_passes_promtool(daemon: RunningDaemon) -> None:
    def scrape() -> str | None:
        with urllib.request.urlopen(daemon.urls["web"] + "metrics", timeout=10) as r:
            text: str = r.read().decode()
        got = samples(text)
        return text if got.get(f"dxboard_board_link_up{{{R}}}") == 1 and \
            f"dxboard_board_input_voltage_volts{{{R}}}" in got else None

    text = wait_until(scrape, 60, "the daemon's metrics with the board link up")
    code, out = promtool("check", "metrics", stdin=text)
    assert code == 0, out
    got = samples(text)
    assert got[f"dxboard_board_input_voltage_volts{{{R}}}"] == pytest.approx(22.2, abs=1.0)
    assert f'dxboard_component_health{{component="hokuyo",{R}}}' in got
    assert f"dxboard_daemon_lag_seconds{{{R}}}" in got
    assert f"dxboard_journal_backlog_entries{{{R}}}" in got


@pytest.mark.parametrize("flag", ["--robot", "--site"])
def test_a_bad_robot_or_site_name_is_one_line_and_exit_2(flag: str) -> None:
    out = subprocess.run([sys.executable, "-m", "host.cli", "run", "models/tedusar", "--emulate",
                          flag, 'a "b"'], capture_output=True, text=True, timeout=60,
                         cwd=Path(__file__).resolve().parents[2])
    assert out.returncode == 2
    assert out.stderr.strip().count("\n") == 0 and flag in out.stderr
    assert "Traceback" not in out.stderr


def test_a_journal_that_cannot_commit_shows_failures_backlog_and_drops(tmp_path: Path) -> None:
    path = tmp_path / "j.sqlite"
    Journal(path).close()
    blocker = sqlite3.connect(path, isolation_level=None)
    blocker.execute("BEGIN EXCLUSIVE")  # another writer holds the file: every commit fails
    journal = Journal(path, max_pending=5, busy_timeout_s=0.05)
    metrics = FleetMetrics(MemoryStatusSource(), robot="rover-1", site="lab", journal=journal)
    try:
        for i in range(8):
            journal.record(Observation(f"ok(c{i})", True), wall=1000.0 + i, mono=float(i))

        def failing() -> dict[str, float] | None:
            got = samples(metrics.render().decode())
            return got if got[f"dxboard_journal_write_failures_total{{{R}}}"] >= 2 else None

        got = wait_until(failing, 60, "two failed commits in the metrics")
        assert got[f"dxboard_journal_backlog_entries{{{R}}}"] == 5
        assert got[f"dxboard_journal_dropped_entries_total{{{R}}}"] == 3
        blocker.execute("COMMIT")
        journal.flush_blocking(timeout=60)
        assert samples(metrics.render().decode())[f"dxboard_journal_backlog_entries{{{R}}}"] \
            <= 1  # at most the note about the loss, recorded after the flush
    finally:
        blocker.close()
        journal.close()


async def test_the_lag_probe_sees_a_loop_that_was_blocked() -> None:
    probe = LagProbe(interval_s=0.2)
    task = asyncio.ensure_future(probe.run())
    try:
        await asyncio.sleep(0)  # the probe is asleep now
        assert probe.lag_s == 0.0
        time.sleep(0.6)  # a blocking call on the loop: the probe wakes at least 0.4 s late
        await wait_until_async(lambda: probe.lag_s > 0, 60, "the probe's next wake")
        assert probe.lag_s >= 0.35
    finally:
        task.cancel()
