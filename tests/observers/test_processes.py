"""Node and property observers against real processes, started and killed here."""

from __future__ import annotations

import subprocess
import time
import uuid
from collections.abc import Callable

from host.diagnosis.observations import Observation
from host.observers import NodeObserver, ObserverHub, ProcessSpec, PropertyObserver
from tests.observers.conftest import PYTHON, Recorder
from tests.wait import wait_until_async


def sleeper(tag: str) -> subprocess.Popen[bytes]:
    """A real process whose command line carries ``tag``."""
    return subprocess.Popen([PYTHON, "-c", "import time; time.sleep(60)", tag])


async def wait_for(cond: Callable[[], bool], timeout: float = 30.0) -> None:
    await wait_until_async(cond, timeout, "the observation", interval=0.01)


async def test_node_by_command_line_match_start_kill_restart() -> None:
    tag = f"dxboard-test-node-{uuid.uuid4().hex}"
    rec = Recorder()
    hub = ObserverHub([NodeObserver("mapper"), PropertyObserver("mapper", cpu_percent=400.0,
                                                                memory_mb=0.5)], rec)
    await hub.start(processes={"mapper": ProcessSpec("mapper", match=tag)}, poll=0.1)
    try:
        await wait_for(lambda: rec.value("running(mapper)") is False)  # not started yet
        proc = sleeper(tag)
        await wait_for(lambda: rec.value("running(mapper)") is True)
        await wait_for(lambda: rec.value("ok(mapper/memory)") is False)  # > 0.5 MB resident
        await wait_for(lambda: rec.value("ok(mapper/cpu)") is True)  # sleeping: little CPU
        proc.kill()
        killed = time.monotonic()
        await wait_for(lambda: rec.value("running(mapper)") is False)
        seen = time.monotonic()
        o = rec.set.get("running(mapper)")
        assert o is not None and killed <= o.time <= seen and o.source == "node:mapper"
        assert rec.value("ok(mapper/cpu)") is None  # a stopped process has no CPU to judge
        proc.wait()
        proc = sleeper(tag)  # a restart is found by the next scan
        await wait_for(lambda: rec.value("running(mapper)") is True)
        proc.kill()
        proc.wait()
    finally:
        await hub.close()


async def test_supervised_node_is_tracked_by_pid() -> None:
    rec = Recorder()
    hub = ObserverHub([NodeObserver("driver")], rec)
    await hub.start(processes={"driver": ProcessSpec("driver", supervised=True)}, poll=5.0)
    proc = sleeper("supervised")
    try:
        assert hub.watcher is not None
        hub.watcher.track("driver", proc.pid)  # what the daemon's supervisor does
        await wait_for(lambda: rec.value("running(driver)") is True)
        proc.terminate()  # not reaped yet: a zombie is not running either
        await wait_for(lambda: rec.value("running(driver)") is False, timeout=30.0)
    finally:
        proc.kill()
        proc.wait()
        await hub.close()


async def test_a_supervised_node_that_died_before_the_watcher_looked_was_running() -> None:
    """A driver that dies at once (its device is off) while the daemon's loop is busy: the
    watcher's next round finds it gone. Its start must still be reported, then its exit, or
    the crash-loop bookkeeping (``host.repair.crashloop``) never sees the run (CI, stop 35:
    the driver was restarted three times and quarantined)."""
    rec = Recorder()
    hub = ObserverHub([NodeObserver("driver")], rec)
    await hub.start(processes={"driver": ProcessSpec("driver", supervised=True)}, poll=5.0)
    try:
        await wait_for(lambda: rec.value("running(driver)") is False)
        seen = len(rec.updates)
        proc = subprocess.Popen([PYTHON, "-c", "import time; time.sleep(0.3)"])
        assert hub.watcher is not None
        hub.watcher.track("driver", proc.pid)  # the supervisor's call, then the loop stalls
        proc.wait()  # ... until the process has ended (blocking: the watcher cannot run)
        await wait_for(lambda: rec.value("running(driver)") is False
                       and len(rec.updates) > seen)
        said = [(u.literal.positive, u.time) for u in rec.updates[seen:]
                if isinstance(u, Observation) and u.literal.atom == "running(driver)"]
        assert [v for v, _ in said][-2:] == [True, False], said
        assert said[-2][1] <= said[-1][1], said
    finally:
        await hub.close()


def test_node_observer_refresh_and_starvation() -> None:
    from host.observers import ProcessSample
    n = NodeObserver("x", validity=3.0, refresh=1.0)
    out = n.feed(ProcessSample("x", True, 42), 10.0)
    assert [(str(o.literal), o.time, o.validity) for o in out] == [("running(x)", 10.0, 3.0)]
    assert n.tick(10.5) == [] and [o.time for o in n.tick(11.0)] == [11.0]
    # the watcher died: no samples for the validity -> retracted, not refreshed forever
    assert n.next_deadline() == 12.0
    n.tick(12.0)
    gone = n.tick(13.0)
    assert [(g.atom, g.time) for g in gone] == [("running(x)", 13.0)]
