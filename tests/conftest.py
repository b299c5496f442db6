"""The suite's two tiers: everything (``make test``) and the in-process tests (``make check``).

About a third of the tests start real processes (the emulated board, the daemon, the robot's
nodes, MicroPython) and spend their time in start-ups and waits; the rest run inside pytest in
seconds. ``pytest --in-process`` runs only the latter, with no list to keep: any test that
starts a process (``subprocess``, asyncio's subprocesses, ``os.fork``, ``os.posix_spawn``) is
stopped at that moment and reported as skipped with the reason "starts a process". ``make
test`` never passes the option, so every test runs there, with its real peers; there each test
module first takes one of the machine's slots (``tests/slots.py``), so that suites side by side
queue their modules instead of starving each other's robots.
"""

from __future__ import annotations

import asyncio
import os
import signal
import subprocess
import threading
from typing import Any

import pytest

from host.lifeline import lifeline
from tests.slots import Slots

_REASON = "starts a process: make test runs it (make check runs only in-process tests)"


def pytest_addoption(parser: pytest.Parser) -> None:
    parser.addoption(
        "--in-process",
        action="store_true",
        help="run only the tests that start no process; a test that starts one is skipped",
    )


_IN_TEST = [False]  # set while a test's setup, call or teardown runs
_SLOTS = Slots()  # this process's hold on a machine-wide slot (tests/slots.py)
_SLOTTED = [False]  # make test: every module runs in a slot; --in-process (make check): none


def _guarded(original: Any) -> Any:
    def guard(*args: Any, **kwargs: Any) -> Any:
        if _IN_TEST[0]:
            pytest.skip(_REASON)
        return original(*args, **kwargs)

    return guard


def _guarded_async(original: Any) -> Any:
    async def guard(*args: Any, **kwargs: Any) -> Any:
        if _IN_TEST[0]:
            pytest.skip(_REASON)
        return await original(*args, **kwargs)

    return guard


def _tie_children_to_the_test_process() -> None:
    """Every process started from the main thread of this pytest process (a worker, under
    xdist) gets SIGTERM from the kernel when that process ends, however it ends
    (``host.lifeline``): a run that is killed (a ``timeout``, Ctrl-C twice, a CI runner's
    kill) leaves no daemon, emulator or robot behind, which a test's ``finally`` cannot
    promise. SIGTERM, not SIGKILL, so a daemon still stops its own children. Only the main
    thread: the kernel sends the signal when the *thread* that started the child ends."""
    original = subprocess.Popen.__init__

    def init(self: subprocess.Popen[Any], *args: Any, **kwargs: Any) -> None:
        if (len(args) < 7 and kwargs.get("preexec_fn") is None
                and threading.current_thread() is threading.main_thread()):
            kwargs["preexec_fn"] = lifeline(signal.SIGTERM)
        original(self, *args, **kwargs)

    subprocess.Popen.__init__ = init  # type: ignore[method-assign]


def pytest_configure(config: pytest.Config) -> None:
    """Processes die with the test process; with --in-process, refuse every process start
    inside a test (its fixtures of every scope included). Outside tests (pytest's and xdist's
    own start-up) processes start as usual. Without it, each test module first takes a slot
    of the machine's (``tests/slots.py``)."""
    _tie_children_to_the_test_process()  # (the xdist controller's workers die with it too)
    if not config.getoption("--in-process"):
        _SLOTTED[0] = True
        return
    if getattr(config.option, "numprocesses", None) and not hasattr(config, "workerinput"):
        return  # the xdist controller: it only starts the workers
    targets: list[tuple[Any, str]] = [(subprocess.Popen, "_execute_child")]
    targets += [(os, n) for n in ("fork", "posix_spawn", "posix_spawnp")]
    for owner, name in targets:
        original = getattr(owner, name)
        setattr(owner, name, _guarded(original))
    # asyncio's subprocesses are refused before the loop makes a transport for them: a
    # transport whose process never started would keep the loop (and a fixture's teardown)
    # waiting for it.
    for name in ("subprocess_exec", "subprocess_shell"):
        setattr(asyncio.base_events.BaseEventLoop, name, _guarded_async(
            getattr(asyncio.base_events.BaseEventLoop, name)))


@pytest.hookimpl(wrapper=True)
def pytest_runtest_protocol(item: pytest.Item, nextitem: pytest.Item | None) -> Any:
    if _SLOTTED[0]:
        _SLOTS.acquire()  # (held already while the module goes on)
    _IN_TEST[0] = True
    try:
        return (yield)
    finally:
        _IN_TEST[0] = False
        if nextitem is None or nextitem.path != item.path:  # the module's fixtures are gone
            _SLOTS.release()


@pytest.fixture(scope="session", autouse=True)
def _suite_cache_dir(tmp_path_factory: pytest.TempPathFactory) -> Any:
    """dxboard keeps parsed domains and models in the user's cache directory: the suite (and
    every process it starts) uses one of its own, never the person's ~/.cache. Tests that
    check the cache itself set a fresh one each."""
    old = os.environ.get("XDG_CACHE_HOME")
    os.environ["XDG_CACHE_HOME"] = str(tmp_path_factory.mktemp("suite-xdg-cache"))
    try:
        yield
    finally:
        if old is None:
            os.environ.pop("XDG_CACHE_HOME", None)
        else:
            os.environ["XDG_CACHE_HOME"] = old
