"""The run-queue wait of real processes (``host.observers.starvation``): a starved process's grows,
a sleeping one's does not; the probe's running total; a topic's chain in the TEDUSAR model.

Real processes on this machine's scheduler: two busy loops pinned to one CPU with
``os.sched_setaffinity`` take turns, so each waits about half the time; a sleeping process
pinned to the same CPU never asks for it. No fixed sleeps: the test waits until the busy pair
has waited a clear amount, then looks at what the sleeper waited meanwhile.
"""

from __future__ import annotations

import os
import subprocess
import sys
import threading
from collections.abc import Iterator
from pathlib import Path

import pytest

from host.diagnosis import load_system
from host.observers.starvation import WaitProbe, chain_of, run_queue_wait
from tests.wait import wait_until

ROOT = Path(__file__).resolve().parents[2]
BUSY = "import time\nend = time.monotonic() + 120\nwhile time.monotonic() < end:\n    pass\n"
SLEEP = "import sys, time\nprint('asleep', flush=True)\ntime.sleep(120)\n"


def _cpu() -> int:
    return min(os.sched_getaffinity(0))


def _start(code: str, cpu: int) -> subprocess.Popen[str]:
    return subprocess.Popen([sys.executable, "-c", code], stdout=subprocess.PIPE, text=True,
                            preexec_fn=lambda: os.sched_setaffinity(0, {cpu}))


@pytest.fixture
def procs() -> Iterator[list[subprocess.Popen[str]]]:
    started: list[subprocess.Popen[str]] = []
    yield started
    for p in started:
        p.kill()
    for p in started:
        p.wait()


def test_two_busy_loops_on_one_cpu_wait_and_a_sleeper_beside_them_does_not(
        procs: list[subprocess.Popen[str]]) -> None:
    cpu = _cpu()
    sleeper = _start(SLEEP, cpu)
    procs.append(sleeper)
    assert sleeper.stdout is not None and sleeper.stdout.readline().strip() == "asleep"
    slept0 = run_queue_wait([sleeper.pid])
    assert slept0 is not None
    procs.extend(_start(BUSY, cpu) for _ in range(2))
    busy = [p.pid for p in procs[1:]]
    # the pair shares one CPU: together they wait about as long as the wall clock runs
    wait_until(lambda: (run_queue_wait(busy) or 0.0) > 0.5, 60.0,
               "the busy pair's run-queue wait to pass 0.5 s")
    slept = run_queue_wait([sleeper.pid])
    assert slept is not None and slept - slept0 < 0.05  # asleep: never runnable


def test_a_process_gone_or_unknown_reads_as_none(procs: list[subprocess.Popen[str]]) -> None:
    p = _start(SLEEP, _cpu())
    procs.append(p)
    assert run_queue_wait([p.pid]) is not None
    p.kill()
    p.wait()
    assert run_queue_wait([p.pid]) is None
    assert run_queue_wait([]) is None
    assert WaitProbe(lambda: [p.pid]).wait() is None


def test_the_probe_of_a_starved_pair_grows_by_its_most_starved_thread(
        procs: list[subprocess.Popen[str]]) -> None:
    procs.extend(_start(BUSY, _cpu()) for _ in range(2))
    pids = [p.pid for p in procs]
    probe = WaitProbe(lambda: pids)
    first = run_queue_wait(pids)
    each0 = [run_queue_wait([pid]) or 0.0 for pid in pids]
    assert probe.read() is not None and first is not None

    def both_waited() -> bool:  # each of the pair, not only one (a busy machine may run one
        return ((probe.wait() or 0.0) > 0.3  # of them alone for a while: the worst wait is
                and all((run_queue_wait([pid]) or 0.0) - w0 > 0.01  # then the sum)
                        for pid, w0 in zip(pids, each0, strict=True)))

    wait_until(both_waited, 60.0, "the pair's worst wait to pass 0.3 s, each having waited")
    # the worst thread's wait, not the sum: less than what the two waited together meanwhile
    worst = probe.wait() or 0.0
    both = (run_queue_wait(pids) or 0.0) - first
    assert 0.3 < worst < both


def _fake_proc(root: Path, threads: dict[tuple[int, int], tuple[int, int, int, bool]]) -> None:
    """A /proc of ``(pid, tid) -> (ns on a CPU, ns waiting, times run, runnable)``."""
    for (pid, tid), (cpu, wait, slices, runnable) in threads.items():
        d = root / str(pid) / "task" / str(tid)
        d.mkdir(parents=True, exist_ok=True)
        (d / "schedstat").write_text(f"{cpu} {wait} {slices}\n")
        (d / "stat").write_text(f"{tid} (a (b) c) {'R' if runnable else 'S'} 1 2 3\n")


def test_the_probe_takes_the_worst_thread_and_sees_one_stuck_on_the_run_queue(
        tmp_path: Path) -> None:
    pids = [10, 20]
    probe = WaitProbe(lambda: pids, proc=str(tmp_path))
    ms = 1_000_000
    _fake_proc(tmp_path, {(10, 10): (5 * ms, 1000 * ms, 9, False),
                          (10, 11): (5 * ms, 500 * ms, 9, True),
                          (20, 20): (5 * ms, 250 * ms, 9, True)})
    assert probe.read() == (0.0, 0)  # a running total: it starts at the first reading
    # thread 10/11 ran (more CPU, one more slice) and waited 200 ms on the way; 20/20 waited
    # 100 ms; 10/10 slept: the chain waited as long as its worst thread
    _fake_proc(tmp_path, {(10, 10): (5 * ms, 1000 * ms, 9, False),
                          (10, 11): (9 * ms, 700 * ms, 10, True),
                          (20, 20): (7 * ms, 350 * ms, 10, True)})
    assert probe.read() == (pytest.approx(0.2), 0)
    # 20/20 runnable at both readings and got no CPU in between: stuck, its wait not yet
    # counted by Linux
    _fake_proc(tmp_path, {(10, 10): (5 * ms, 1000 * ms, 9, False),
                          (10, 11): (12 * ms, 700 * ms, 11, False),
                          (20, 20): (7 * ms, 350 * ms, 10, True)})
    assert probe.read() == (pytest.approx(0.2), 1)
    pids[1] = 30  # the node restarted: a new pid, whose counts start with it
    _fake_proc(tmp_path, {(30, 30): (1 * ms, 5 * ms, 1, True)})
    assert probe.read() == (pytest.approx(0.2), 0)  # no jump either way
    _fake_proc(tmp_path, {(30, 30): (2 * ms, 105 * ms, 2, False)})
    assert probe.read() == (pytest.approx(0.3), 0)


def test_the_callers_own_thread_is_never_stuck(tmp_path: Path) -> None:
    me = (os.getpid(), threading.get_native_id())
    probe = WaitProbe(lambda: [me[0]], proc=str(tmp_path))
    _fake_proc(tmp_path, {me: (1, 2, 3, True), (me[0], 1): (1, 2, 3, True)})
    assert probe.read() == (0.0, 0)
    # runnable (it is reading) and, to its own eyes, no CPU in between; another thread the same
    assert probe.read() == (0.0, 1)


def test_the_callers_own_wait_on_the_run_queue_counts(tmp_path: Path) -> None:
    """The daemon reads its own process: its loop thread held up on the run queue holds up
    every message queued behind it, so its wait is the chain's as much as a node's."""
    ms = 1_000_000
    me = (os.getpid(), threading.get_native_id())
    probe = WaitProbe(lambda: [me[0]], proc=str(tmp_path))
    _fake_proc(tmp_path, {me: (1 * ms, 10 * ms, 3, True), (me[0], 1): (1 * ms, 1 * ms, 2, False)})
    assert probe.read() == (0.0, 0)
    _fake_proc(tmp_path, {me: (5 * ms, 410 * ms, 9, True), (me[0], 1): (2 * ms, 1 * ms, 3, False)})
    assert probe.read() == (pytest.approx(0.4), 0)


def test_a_topics_chain_is_its_publishers_their_inputs_and_their_devices() -> None:
    model = load_system(ROOT / "models" / "tedusar")
    assert chain_of(model, "/scan") == (["hokuyo_node"], ["hokuyo"])
    nodes, devices = chain_of(model, "/cmd_vel")
    assert sorted(nodes) == ["jaguar_teleop_node", "joy_node"] and devices == ["joystick"]
    nodes, devices = chain_of(model, "/map")
    assert "hector_mapping" in nodes and "hokuyo_node" in nodes and "hokuyo" in devices
    assert chain_of(model, "/nobody") == ([], [])
