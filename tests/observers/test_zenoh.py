"""End to end over real Zenoh peers on loopback: driver processes publish, the hub observes.

The hub's source is a zenoh session listening on a free loopback port, multicast scouting off;
publishers are real OS processes (``python -m host.observers.publisher``) connecting to it.
"""

from __future__ import annotations

import subprocess
import time
from collections.abc import AsyncIterator, Callable

import pytest

from host.observers import (
    DiagnosticObserver,
    FrequencyObserver,
    MatchObserver,
    ObserverHub,
    ResponseObserver,
    Threshold,
    TrendObserver,
    ValueRef,
)
from host.observers.publisher import TopicPublisher
from host.observers.sources.zenoh_peer import ZenohSource
from tests.observers.conftest import PYTHON, Recorder
from tests.wait import wait_until_async


def publisher(endpoint: str, topic: str, rate: float, *values: str) -> subprocess.Popen[bytes]:
    args = [PYTHON, "-m", "host.observers.publisher", "--connect", endpoint, "--rate", str(rate),
            topic]
    for v in values:
        args += ["--value", v]
    return subprocess.Popen(args)


async def wait_for(cond: Callable[[], bool], each: Callable[[], None] | None = None) -> None:
    """Wait until ``cond``; call ``each`` every round (re-publishing: the first message on a
    key that was just declared may reach a new peer before its routes exist)."""
    await wait_until_async(cond, what="the observation", each=each)


@pytest.fixture
async def source(endpoint: str) -> AsyncIterator[ZenohSource]:
    src = ZenohSource(listen=[endpoint])
    yield src
    src.close()


async def test_frequency_trend_and_match_from_publisher_processes(
        source: ZenohSource, endpoint: str) -> None:
    rec = Recorder()
    odom = FrequencyObserver("/odom", rate=50, tolerance=15, window=0.5, silence=5)
    yaw = TrendObserver(ValueRef("odom_yaw_rate", "/odom", "yaw"), window=0.5, slope=0.1)
    imu = ValueRef("imu_yaw_rate", "/imu_data", "yaw")
    match = MatchObserver(yaw.value, imu, window=0.5, slope=0.1)
    hub = ObserverHub([odom, yaw, match], rec)
    await hub.start(source)
    procs = [publisher(endpoint, "/odom", 50, "yaw=1.0*t"),
             publisher(endpoint, "/imu_data", 50, "yaw=2.0*t")]
    try:
        await wait_for(lambda: rec.value("ok(/odom)") is True
                       and rec.value("matched(odom_yaw_rate,imu_yaw_rate)") is True)
        assert rec.value("inc(odom_yaw_rate)") is True
        assert rec.value("dec(odom_yaw_rate)") is False
        assert odom.frequency is not None and abs(odom.frequency - 50) < 15
        procs[0].kill()
        procs[0].wait()
        killed = time.monotonic()
        await wait_for(lambda: rec.value("ok(/odom)") is False)
        o = rec.set.get("ok(/odom)")
        assert o is not None and o.source == "frequency:/odom"
        # stamped at its deadline: 5 periods after the last message, before we saw it
        assert o.time <= time.monotonic() and o.time >= killed - 0.5
        # the odometry trend has no samples left: unknown, and so is the match
        await wait_for(lambda: rec.value("inc(odom_yaw_rate)") is None
                       and rec.value("matched(odom_yaw_rate,imu_yaw_rate)") is None)
    finally:
        for p in procs:
            p.kill()
            p.wait()
        await hub.close()
    assert len(rec.set) == 0  # closing retracts everything the observers said


async def test_diagnostic_and_response_through_an_in_process_publisher(
        source: ZenohSource, endpoint: str) -> None:
    rec = Recorder()
    diag = DiagnosticObserver("/diagnostics", [Threshold("temp", "ok(temp_cpu1)", max=40.0)])
    resp = ResponseObserver("/cmd_vel", "/odom", within=0.3)
    hub = ObserverHub([diag, resp], rec)
    await hub.start(source)
    with TopicPublisher(connect=[endpoint]) as pub:
        await wait_for(lambda: bool(source.session.info.peers_zid()))
        await wait_for(lambda: rec.value("ok(temp_cpu1)") is True,
                       each=lambda: pub.put("/diagnostics", {"temp": 35.0}))
        await wait_for(lambda: rec.value("ok(temp_cpu1)") is False,
                       each=lambda: pub.put("/diagnostics", {"temp": 45.0}))

        def command_and_answer() -> None:
            pub.put("/cmd_vel", {"v": 1})
            pub.put("/odom", {"v": 1})

        await wait_for(lambda: rec.value("ok(/odom)") is True, each=command_and_answer)
        sent = time.monotonic()
        # no odometry follows (a command again each round: a late answer to an earlier one
        # on a loaded machine must not leave the observer satisfied)
        await wait_for(lambda: rec.value("ok(/odom)") is False,
                       each=lambda: pub.put("/cmd_vel", {"v": 2}))
        o = rec.set.get("ok(/odom)")
        assert o is not None and o.time >= sent + 0.3 - 0.05
    await hub.close()
