"""The machine-wide slots of process-starting test modules (``tests/slots.py``): a slot is
held by one process at a time, a waiter gets it when it is given back or its holder dies, and
the wait does not count against the test's time limit."""

from __future__ import annotations

import signal
import subprocess
import sys
import threading
import time
from pathlib import Path

from tests.slots import Slots, paused_alarm
from tests.wait import wait_until


def test_a_slot_is_held_once_and_taken_again_when_given_back(tmp_path: Path) -> None:
    a, b = Slots(tmp_path, n=2), Slots(tmp_path, n=2)
    c = Slots(tmp_path, n=2)
    assert a.try_acquire() and b.try_acquire()
    assert not c.try_acquire()  # both taken
    a.release()
    assert c.try_acquire() and c.held
    assert a.try_acquire() is False
    b.release()
    c.release()


def test_a_waiter_gets_the_slot_its_holder_gives_back(tmp_path: Path) -> None:
    holder, waiter = Slots(tmp_path, n=1), Slots(tmp_path, n=1)
    assert holder.try_acquire()
    got = threading.Event()

    def wait() -> None:
        waiter.acquire()
        got.set()

    t = threading.Thread(target=wait, daemon=True)
    t.start()
    assert not got.wait(0.5)  # it waits while the slot is held ...
    holder.release()
    wait_until(got.is_set, 60, "the waiter took the slot given back")
    t.join(60)
    assert waiter.held and waiter.waited_s > 0
    waiter.release()


def test_a_dead_holders_slot_is_free(tmp_path: Path) -> None:
    code = ("import sys, time; from pathlib import Path; from tests.slots import Slots; "
            f"s = Slots(Path({str(tmp_path)!r}), n=1); assert s.try_acquire(); "
            "print('held', flush=True); time.sleep(600)")
    proc = subprocess.Popen([sys.executable, "-c", code], stdout=subprocess.PIPE, text=True,
                            cwd=Path(__file__).resolve().parents[1])
    try:
        assert proc.stdout is not None and proc.stdout.readline().strip() == "held"
        mine = Slots(tmp_path, n=1)
        assert not mine.try_acquire()
        proc.kill()
        proc.wait(60)
        wait_until(mine.try_acquire, 60, "the dead process's slot free")
        mine.release()
    finally:
        proc.kill()
        proc.wait(60)


def test_the_wait_does_not_count_against_the_time_limit() -> None:
    saved = signal.getitimer(signal.ITIMER_REAL)  # pytest-timeout's own, given back after
    old = signal.signal(signal.SIGALRM, lambda *_: None)
    try:
        signal.setitimer(signal.ITIMER_REAL, 100.0)
        before = signal.getitimer(signal.ITIMER_REAL)[0]
        start = time.monotonic()
        with paused_alarm():
            assert signal.getitimer(signal.ITIMER_REAL)[0] == 0.0  # stopped inside
            time.sleep(0.5)  # time that must not count
        outside = time.monotonic() - start - 0.5  # what passed outside the pause, at most
        after = signal.getitimer(signal.ITIMER_REAL)[0]
        assert after >= before - outside - 0.05, (before, after)
    finally:
        signal.signal(signal.SIGALRM, old)
        signal.setitimer(signal.ITIMER_REAL, *saved)


def test_where_slots_cannot_be_used_the_suite_goes_on_without_them(tmp_path: Path) -> None:
    not_a_directory = tmp_path / "file"
    not_a_directory.write_text("")
    slots = Slots(not_a_directory, n=1)
    assert slots.try_acquire()  # no wait, and no slot held: as without slots
    slots.acquire()
    slots.release()
    assert not slots.held


def test_the_directory_is_open_to_every_user(tmp_path: Path) -> None:
    slots = Slots(tmp_path / "slots", n=1)
    assert slots.try_acquire()
    assert (tmp_path / "slots").stat().st_mode & 0o7777 == 0o1777
    slots.release()
