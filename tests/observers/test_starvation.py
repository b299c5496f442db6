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
from host.observers.starvation import WaitProbe, chain_of, read_chain, run_queue_wait
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


def test_a_busy_thread_is_runnable_and_the_callers_own_is_left_out(
        procs: list[subprocess.Popen[str]]) -> None:
    busy = _start(BUSY, _cpu())
    procs.append(busy)
    state = wait_until(lambda: read_chain([busy.pid]), 60.0, "a reading of the busy loop")
    assert state.runnable == 1  # a busy loop is always running or waiting to
    me = read_chain([os.getpid()], skip=threading.get_native_id())
    assert me is not None and me.runnable == 0  # this thread runs, the others sleep


def _fake_proc(root: Path, waits: dict[int, list[int]], runnable: tuple[int, ...] = ()) -> None:
    """A /proc of ``pid -> [each thread's wait, ns]``; threads ``runnable`` (tids) in state R."""
    for pid, threads in waits.items():
        for i, ns in enumerate(threads):
            tid = pid + i
            d = root / str(pid) / "task" / str(tid)
            d.mkdir(parents=True, exist_ok=True)
            (d / "schedstat").write_text(f"123 {ns} 7\n")
            state = "R" if tid in runnable else "S"
            (d / "stat").write_text(f"{tid} (a (b) c) {state} 1 2 3\n")


def test_the_probe_sums_threads_and_keeps_counting_across_a_restart(tmp_path: Path) -> None:
    pids = [10, 20]
    probe = WaitProbe(lambda: pids, proc=str(tmp_path))
    _fake_proc(tmp_path, {10: [1_000_000_000, 500_000_000], 20: [250_000_000]})
    assert probe.wait() == 0.0  # a running total: it starts at the first reading
    _fake_proc(tmp_path, {10: [1_200_000_000, 500_000_000], 20: [350_000_000]})
    assert probe.wait() == pytest.approx(0.3)  # 0.2 + 0.1 s more, over both processes
    _fake_proc(tmp_path, {10: [1_200_000_000, 500_000_000], 20: [350_000_000]}, (11, 20))
    got = probe.read()
    assert got is not None and got.runnable == 2 and got.wait == pytest.approx(0.3)
    pids[1] = 30  # the node restarted: a new pid whose count starts anew
    _fake_proc(tmp_path, {30: [5_000_000]})
    assert probe.wait() == pytest.approx(0.3)  # no jump either way
    _fake_proc(tmp_path, {30: [105_000_000]})
    assert probe.wait() == pytest.approx(0.4)


def test_a_topics_chain_is_its_publishers_their_inputs_and_their_devices() -> None:
    model = load_system(ROOT / "models" / "tedusar")
    assert chain_of(model, "/scan") == (["hokuyo_node"], ["hokuyo"])
    nodes, devices = chain_of(model, "/cmd_vel")
    assert sorted(nodes) == ["jaguar_teleop_node", "joy_node"] and devices == ["joystick"]
    nodes, devices = chain_of(model, "/map")
    assert "hector_mapping" in nodes and "hokuyo_node" in nodes and "hokuyo" in devices
    assert chain_of(model, "/nobody") == ([], [])
