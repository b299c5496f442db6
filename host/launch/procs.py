"""A child process of the launcher: start it, know when it is ready, stop it in bounded time.

Every process dxboard's launcher starts for a robot — the emulated board (``dxboard emulate``),
a daemon (``dxboard run``), and the servers the tests and benchmarks start beside them — is a
``Child``. ``Child(argv, ...)`` starts it (``subprocess.Popen``) in a session of its own (so a
terminal's Ctrl-C reaches only whom it is meant for, and a whole group can be signalled) and,
when started from the main thread (or asked to from another), tied to this process by
``host.lifeline`` (it gets SIGTERM from the kernel when we end, however we end; the kernel sends
the signal when the *thread* that started the child ends, so a pool's thread must not tie it). A
thread per output stream reads every line as it comes, so a full pipe never stalls the child:
stdout's lines are kept (``lines``; ``name: url`` lines are read by ``urls()``/``devices()``),
stderr's go to a file or, when none is given, to the log (the last ones kept for an error
message). ``wait_ready(ready, timeout)`` waits until ``ready(child)`` holds (a line printed, a
port open), False if the child exited first, ``TimeoutError`` at the deadline. ``stop()`` is the
bounded escalation: a signal (SIGTERM by default), ``grace_s`` to exit, then SIGKILL (to the
whole group when asked). The coroutines ``aready``/``astop`` are the same, off the event loop.
``Printed`` is the base of what a launcher hands out for a child that prints its URLs.
"""

from __future__ import annotations

import asyncio
import collections
import contextlib
import logging
import os
import signal
import subprocess
import threading
import time
from collections.abc import Callable, Mapping, Sequence
from pathlib import Path
from typing import IO

from host.lifeline import lifeline

log = logging.getLogger(__name__)

READ_JOIN_S = 5.0  # how long a stop waits for the readers of a child's (closed) output
SETTLE_POLL_S = 0.05  # how often readiness is asked again without a new line


def url_lines(lines: Sequence[str]) -> tuple[dict[str, str], dict[str, str]]:
    """The ``name: url`` lines (every other name) and ``device: NAME URL`` lines of ``lines``."""
    urls: dict[str, str] = {}
    devices: dict[str, str] = {}
    for line in lines:
        name, _, rest = line.strip().partition(": ")
        if name == "device":
            dev, _, url = rest.partition(" ")
            devices[dev] = url
        elif rest:
            urls[name] = rest
    return urls, devices


class Child:
    """One started process; see the module."""

    def __init__(self, argv: Sequence[str], *, env: Mapping[str, str] | None = None,
                 cwd: Path | None = None, stderr: Path | None = None, name: str = "",
                 own_session: bool = True, tie: int = signal.SIGTERM,
                 merge_stderr: bool = False, keep_err: int = 50,
                 any_thread: bool = False) -> None:
        """``stderr``: a file its stderr is appended to (default: the log; ``merge_stderr``:
        into ``lines`` with stdout, in the order written). ``tie``: the signal the kernel
        sends it when this process ends (``host.lifeline``), if started from the main thread or
        ``any_thread`` (then it dies with the thread that started it: right for an event
        loop's thread, wrong for a pool's). ``keep_err``: how many of its last stderr lines
        ``err_tail`` keeps."""
        self.argv = list(argv)
        self.name = name or Path(self.argv[0]).name
        self.lines: list[str] = []  # stdout, one entry per line, as they come
        self.err_tail: collections.deque[str] = collections.deque(maxlen=keep_err)
        self.group = own_session
        self._changed = threading.Condition()
        self._last_line = time.monotonic()
        self._eof = False
        tied = (lifeline(tie) if any_thread
                or threading.current_thread() is threading.main_thread() else None)
        err_file: IO[bytes] | None = stderr.open("ab") if stderr is not None else None
        try:
            self.proc = subprocess.Popen(
                self.argv, cwd=cwd, env=dict(env) if env is not None else None,
                stdout=subprocess.PIPE,
                stderr=(subprocess.STDOUT if merge_stderr else
                        err_file if err_file is not None else subprocess.PIPE),
                preexec_fn=tied, start_new_session=own_session)
        finally:
            if err_file is not None:
                err_file.close()  # the child holds its own copy
        self._readers = [threading.Thread(target=self._read_out, daemon=True,
                                          name=f"{self.name}-stdout")]
        if self.proc.stderr is not None:
            self._readers.append(threading.Thread(target=self._read_err, daemon=True,
                                                  name=f"{self.name}-stderr"))
        for reader in self._readers:
            reader.start()

    @property
    def pid(self) -> int:
        return self.proc.pid

    def _read_out(self) -> None:
        assert self.proc.stdout is not None
        for raw in self.proc.stdout:
            with self._changed:
                self.lines.append(raw.decode(errors="replace").rstrip("\n"))
                self._last_line = time.monotonic()
                self._changed.notify_all()
        with self._changed:
            self._eof = True
            self._changed.notify_all()

    def _read_err(self) -> None:
        assert self.proc.stderr is not None
        for raw in self.proc.stderr:
            line = raw.decode(errors="replace").rstrip("\n")
            self.err_tail.append(line)
            log.debug("%s: %s", self.name, line)

    def urls(self) -> dict[str, str]:
        """The ``name: url`` lines it printed so far (the last of each name)."""
        return url_lines(list(self.lines))[0]

    def devices(self) -> dict[str, str]:
        """The ``device: NAME URL`` lines it printed so far."""
        return url_lines(list(self.lines))[1]

    def wait_ready(self, ready: Callable[[Child], bool], timeout: float,
                   settle_s: float = 0.0, poll_s: float = SETTLE_POLL_S) -> bool:
        """Wait until ``ready(self)`` holds and no new line came for ``settle_s`` (the rest of
        a block printed at once); False if its output ended first (it exited), TimeoutError
        at ``timeout``. ``ready`` is asked on every line and every ``poll_s`` (a port's
        state), never while a reader waits to add a line."""
        end = time.monotonic() + timeout
        while True:
            with self._changed:
                eof, last_line, seen = self._eof, self._last_line, len(self.lines)
            now = time.monotonic()
            if ready(self):
                if eof or now - last_line >= settle_s:
                    return True
            elif eof:
                return False
            if now >= end:
                raise TimeoutError(f"{self.name} not ready after {timeout:g} s")
            with self._changed:
                if len(self.lines) == seen and not self._eof:
                    self._changed.wait(poll_s)

    def running(self) -> bool:
        return self.proc.poll() is None

    def send(self, sig: int, group: bool = False) -> None:
        """Send ``sig`` to it (``group``: to its whole process group), if it still runs."""
        if self.proc.poll() is not None:
            return
        with contextlib.suppress(ProcessLookupError):
            if group and self.group:
                os.killpg(self.proc.pid, sig)
            else:
                self.proc.send_signal(sig)

    def stop(self, sig: int = signal.SIGTERM, grace_s: float = 20.0,
             group: bool = False) -> int:
        """``sig``, up to ``grace_s`` to exit, then SIGKILL; its exit code. Idempotent."""
        if self.proc.poll() is None:
            self.send(sig, group)
            try:
                self.proc.wait(grace_s)
            except subprocess.TimeoutExpired:
                log.warning("%s did not exit %g s after signal %d: killing it", self.name,
                            grace_s, sig)
                self.send(signal.SIGKILL, group)
                self.proc.wait()
        self.close_pipes()
        return self.proc.returncode

    def close_pipes(self) -> None:
        """Wait (bounded) for the readers of its output, then close the pipes."""
        for reader in self._readers:
            reader.join(READ_JOIN_S)  # a grandchild may hold the pipe open: never hang on it
        for pipe in (self.proc.stdout, self.proc.stderr):
            if pipe is not None and not any(r.is_alive() for r in self._readers):
                pipe.close()

    async def aready(self, ready: Callable[[Child], bool], timeout: float,
                     settle_s: float = 0.0) -> bool:
        """``wait_ready`` without blocking the event loop."""
        return await asyncio.to_thread(self.wait_ready, ready, timeout, settle_s)

    async def astop(self, sig: int = signal.SIGTERM, grace_s: float = 20.0,
                    group: bool = False) -> int:
        """``stop`` without blocking the event loop."""
        return await asyncio.to_thread(self.stop, sig, grace_s, group)


class Printed:
    """A started child that printed ``name: url`` lines: its process, URLs and devices."""

    child: Child

    @property
    def proc(self) -> subprocess.Popen[bytes]:
        return self.child.proc

    @property
    def urls(self) -> dict[str, str]:
        """Every ``name: url`` line it printed (board, control, ...)."""
        return self.child.urls()

    @property
    def devices(self) -> dict[str, str]:
        """Device name -> URL."""
        return self.child.devices()
