"""SIGINT and SIGTERM that are never lost, and a stop that always ends (daemon and nodes).

asyncio's ``loop.add_signal_handler`` learns *which* signal arrived from the byte the C-level
handler writes into the loop's self-pipe, the same pipe every ``call_soon_threadsafe`` writes
a byte into. When middleware threads filled it while the loop was held up, the byte of SIGINT
was refused (``Exception ignored when trying to write to the signal wakeup fd:
BlockingIOError``) and the signal was gone (issue 25, item 1). So the daemon does not use it.

``StopSignals(loop, on_stop)`` installs plain ``signal.signal`` handlers for SIGINT and SIGTERM
and points ``signal.set_wakeup_fd`` at a socket pair of its own, which only signals write to
(one byte each; nothing else can fill it). A thread of its own (``signals``) reads that socket,
so it hears a signal even while the event loop, or the main thread, is held up:

- the first SIGINT/SIGTERM asks the loop to stop (``on_stop`` via ``call_soon_threadsafe``,
  which never loses its callback: a full self-pipe only loses the wakeup byte, and a full pipe
  wakes the loop anyway); if the loop has not run it after ``NUDGE_S`` the thread says so and
  asks again;
- a second SIGINT/SIGTERM stops at once: every child process (and its process group) is
  killed, one line says so on stderr, and the process exits with ``EXIT_SECOND`` (130);
- a stop still running ``deadline_s`` after the first signal (or after ``begin()``, a stop for
  another reason, such as a failed task) is cut short the same way (exit ``EXIT_DEADLINE``,
  124), so that no stage, however stuck, keeps the daemon from ending; ``done()`` (the orderly
  stop finished) stands the watchdog down.

Other signals can be routed through the same socket (``on(signum, callback)``: the callback
runs on the loop), for the SIGUSR2 memory probe. ``close()`` restores the previous handlers and
wakeup fd.
"""

from __future__ import annotations

import asyncio
import contextlib
import logging
import os
import signal
import socket
import threading
import time
from collections.abc import Callable
from types import FrameType

import psutil

log = logging.getLogger(__name__)

STOP_SIGNALS = (signal.SIGINT, signal.SIGTERM)
DEADLINE_S = 9.0  # first signal -> exit, whatever happens (below systemd's TimeoutStopSec)
NUDGE_S = 3.0  # the loop has not reacted to the stop request: say so, ask again
EXIT_SECOND = 130  # a second Ctrl-C: 128 + SIGINT, as shells report an interrupted command
EXIT_DEADLINE = 124  # the stop overran its deadline (as timeout(1) reports a timeout)


def kill_children() -> list[int]:
    """SIGKILL every descendant of this process (each child's process group too: the nodes
    run in sessions of their own); returns the pids that were killed."""
    try:
        kids = psutil.Process().children(recursive=True)
    except psutil.Error:
        return []
    killed = []
    for p in kids:
        with contextlib.suppress(OSError):
            if os.getpgid(p.pid) == p.pid:
                os.killpg(p.pid, signal.SIGKILL)
        with contextlib.suppress(OSError):
            os.kill(p.pid, signal.SIGKILL)
            killed.append(p.pid)
    return killed


def _exit_now(code: int, why: str) -> None:
    """Kill the children, say ``why`` in one line on stderr and end the process."""
    killed = kill_children()
    with contextlib.suppress(OSError):
        os.write(2, f"dxboard: {why}; stopped at once"
                    f"{f' ({len(killed)} child processes killed)' if killed else ''}, "
                    f"exit {code}\n".encode())
    os._exit(code)


def _ignore(signum: int, frame: FrameType | None) -> None:
    """The Python-level handler: the work is done by the ``signals`` thread."""


class StopSignals:
    def __init__(self, loop: asyncio.AbstractEventLoop, on_stop: Callable[[], None],
                 deadline_s: float = DEADLINE_S, nudge_s: float = NUDGE_S,
                 exit_now: Callable[[int, str], None] = _exit_now) -> None:
        self.loop = loop
        self.on_stop = on_stop
        self.deadline_s = deadline_s
        self.nudge_s = nudge_s
        self.exit_now = exit_now
        self.received: list[int] = []  # stop signals, in order
        self._extra: dict[int, Callable[[], None]] = {}
        self._acked = threading.Event()  # the loop ran on_stop
        self._done = threading.Event()  # the orderly stop finished
        self._first = 0.0
        self._old: dict[int, object] = {}
        self._old_fd = -1
        self._rsock, self._wsock = socket.socketpair()
        self._wsock.setblocking(False)
        self._rsock.settimeout(0.5)
        self._thread = threading.Thread(target=self._run, name="signals", daemon=True)
        self._closed = False

    def install(self) -> StopSignals:
        """Take over SIGINT and SIGTERM (call it on the main thread)."""
        self._old_fd = signal.set_wakeup_fd(self._wsock.fileno(), warn_on_full_buffer=False)
        for sig in (*STOP_SIGNALS, *self._extra):
            self._old[sig] = signal.signal(sig, _ignore)
        self._thread.start()
        return self

    def on(self, signum: int, callback: Callable[[], None]) -> None:
        """Run ``callback`` on the loop at each ``signum`` (before or after ``install``)."""
        self._extra[signum] = callback
        if self._thread.is_alive():
            self._old.setdefault(signum, signal.signal(signum, _ignore))

    def begin(self) -> None:
        """A stop has begun without a signal (the daemon failed): arm the watchdog all the
        same, so that this stop is bounded too."""
        if not self._first:
            self._first = time.monotonic()

    def done(self) -> None:
        """The orderly stop has finished: the watchdog stands down."""
        self._done.set()

    def close(self) -> None:
        """Restore the earlier handlers and wakeup fd (main thread; idempotent)."""
        if self._closed:
            return
        self._closed = True
        self._done.set()
        signal.set_wakeup_fd(self._old_fd)
        for sig, old in self._old.items():
            with contextlib.suppress(TypeError, ValueError):
                signal.signal(sig, old)  # type: ignore[arg-type]
        self._thread.join(2.0)
        self._rsock.close()
        self._wsock.close()

    # -- the signals thread --------------------------------------------------------------
    def _run(self) -> None:
        nudged = 0.0
        while not self._closed:
            try:
                data = self._rsock.recv(64)
            except TimeoutError:
                data = b""
            except OSError:
                return
            for signum in data:
                self._heard(signum)
            if not self._first or self._done.is_set():
                continue
            waited = time.monotonic() - self._first
            if waited >= self.deadline_s:
                self.exit_now(EXIT_DEADLINE, f"the stop took longer than {self.deadline_s:g} s"
                              " (what it waited for is logged above)")
                return
            if (self.received and not self._acked.is_set()
                    and waited - nudged >= self.nudge_s):
                nudged = waited
                log.warning("the event loop has not reacted to %s for %.0f s; asked again",
                            signal.Signals(self.received[0]).name, waited)
                self._request()

    def _heard(self, signum: int) -> None:
        if signum in self._extra:
            with contextlib.suppress(RuntimeError):
                self.loop.call_soon_threadsafe(self._extra[signum])
            return
        if signum not in STOP_SIGNALS:
            return
        self.received.append(signum)
        name = signal.Signals(signum).name
        if len(self.received) == 1:
            self.begin()
            self._request()
        elif not self._done.is_set():
            self.exit_now(EXIT_SECOND, f"a second {name} during the stop")

    def _request(self) -> None:
        with contextlib.suppress(RuntimeError):  # the loop closed: the stop is over anyway
            self.loop.call_soon_threadsafe(self._stop_on_loop)

    def _stop_on_loop(self) -> None:
        if not self._acked.is_set():
            self._acked.set()
            self.on_stop()

