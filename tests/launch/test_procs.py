"""The launcher's child process (``host.launch.procs.Child``) with real processes: readiness read
from what it prints, the end of its output when it exits first, a stop that escalates to
SIGKILL when the child ignores the signal, a whole group stopped, and a child tied to the
thread that started it (``host.lifeline``) gone with that thread. Deadlines are generous
(they bound a failure, never decide a pass); the children are tiny Python scripts."""

from __future__ import annotations

import signal
import sys
import threading
from collections.abc import Iterator
from contextlib import contextmanager

import psutil
import pytest

from host.launch.procs import Child, url_lines
from host.launch.waiting import wait_until

LONG_S = 120.0


@contextmanager
def child(script: str) -> Iterator[Child]:
    c = Child([sys.executable, "-u", "-c", script], name="script")
    try:
        yield c
    finally:
        c.stop(signal.SIGKILL, 10)


PRINTS = """
import sys, time
print("board: tcp://127.0.0.1:1")
print("control: control://127.0.0.1:2")
print("device: hokuyo tcp://127.0.0.1:3")
sys.stdout.flush()
time.sleep(600)
"""


def test_it_is_ready_once_it_printed_its_urls_and_keeps_every_line() -> None:
    with child(PRINTS) as c:
        assert c.wait_ready(lambda ch: "control" in ch.urls(), LONG_S, settle_s=0.2)
        assert c.urls() == {"board": "tcp://127.0.0.1:1", "control": "control://127.0.0.1:2"}
        assert c.devices() == {"hokuyo": "tcp://127.0.0.1:3"}
        assert c.running()


def test_a_child_that_exits_before_it_is_ready_is_not_ready() -> None:
    with child("import sys; print('board: x'); sys.stderr.write('it broke\\n'); "
               "sys.exit(3)") as c:
        assert not c.wait_ready(lambda ch: "control" in ch.urls(), LONG_S)
        assert c.stop() == 3
        assert list(c.err_tail) == ["it broke"]


def test_a_child_that_never_gets_ready_times_out() -> None:
    with child("import time; time.sleep(600)") as c, pytest.raises(TimeoutError):
        c.wait_ready(lambda ch: False, 0.5)


IGNORES = """
import signal, sys, time
signal.signal(signal.SIGTERM, signal.SIG_IGN)
print("ignoring", flush=True)
time.sleep(600)
"""


def test_a_stop_the_child_ignores_ends_in_sigkill() -> None:
    with child(IGNORES) as c:
        assert c.wait_ready(lambda ch: bool(ch.lines), LONG_S)
        assert c.stop(signal.SIGTERM, grace_s=0.5) == -signal.SIGKILL
        assert not c.running()
        assert c.stop() == -signal.SIGKILL  # idempotent


GROUP = """
import subprocess, sys, time
kid = subprocess.Popen([sys.executable, "-c", "import time; time.sleep(600)"])
print(f"kid: {kid.pid}", flush=True)
time.sleep(600)
"""


def test_a_group_stop_reaches_the_childs_own_children() -> None:
    with child(GROUP) as c:
        assert c.wait_ready(lambda ch: "kid" in ch.urls(), LONG_S)
        kid = psutil.Process(int(c.urls()["kid"]))
        assert c.stop(signal.SIGTERM, 30, group=True) == -signal.SIGTERM
        kid.wait(LONG_S)  # psutil.TimeoutExpired (a failure) if the group stop missed it


def test_url_lines_reads_names_and_devices() -> None:
    assert url_lines(["board: tcp://a:1", "device: d1 tcp://b:2", "noise", "web: http://c/"]) \
        == ({"board": "tcp://a:1", "web": "http://c/"}, {"d1": "tcp://b:2"})


def test_a_child_tied_to_a_thread_gets_sigterm_when_that_thread_ends() -> None:
    started: list[Child] = []
    raised: list[BaseException] = []

    def start() -> None:
        try:
            started.append(Child([sys.executable, "-c", "import time; time.sleep(600)"],
                                 any_thread=True))
        except BaseException as exc:  # e.g. --in-process's skip: raised again in the test
            raised.append(exc)

    t = threading.Thread(target=start)
    t.start()
    t.join()
    if raised:
        raise raised[0]
    try:
        wait_until(lambda: not started[0].running(), LONG_S, "the tied child gone")
        assert started[0].proc.returncode == -signal.SIGTERM
    finally:
        started[0].stop(signal.SIGKILL, 10)
