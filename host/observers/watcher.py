"""The process watcher: finds each node's process and reports ``ProcessSample`` values.

A node's process is named in ``system.yaml`` by ``pid``, by ``match`` (a regular expression
searched in the command line, as ``pgrep -f`` does) or as ``supervised`` (the daemon starts it
and calls ``track(node, pid)``). Every ``poll`` seconds the watcher samples the known
processes (CPU percent since the previous sample, resident memory) and, for nodes without a
live process, scans the process table. An exit is not left to the next poll: for every
process found the watcher opens a Linux pidfd (``os.pidfd_open``) and adds it to the event
loop, which wakes the watcher the moment the process ends (exited, killed, or a zombie not
yet reaped), so ``¬running(n)`` follows within milliseconds.

Why psutil rather than reading ``/proc``: the same calls give command lines, CPU times with
per-process percent bookkeeping, resident memory and zombie status, on Linux and elsewhere
(a development laptop), without parsing ``/proc/<pid>/stat`` field by field; the scan of a few
hundred processes every 0.5 s costs a few milliseconds. Where pidfd is missing (not Linux, or
a kernel older than 5.3) exits are seen at the next poll.

The watcher is I/O: it reads its clock (``clock``) to stamp samples and calls ``on_sample``
for each; the observers stay pure.
"""

from __future__ import annotations

import asyncio
import contextlib
import logging
import os
import re
import time
from collections.abc import Callable, Mapping

import psutil

from host.observers.processes import DEFAULT_POLL as DEFAULT_POLL
from host.observers.processes import ProcessSample
from host.observers.processes import ProcessSpec as ProcessSpec

log = logging.getLogger(__name__)



class _Tracked:
    def __init__(self, proc: psutil.Process) -> None:
        self.proc = proc
        self.fd: int | None = None
        with contextlib.suppress(psutil.Error):
            proc.cpu_percent(None)  # starts the CPU bookkeeping; the first value is 0


class ProcessWatcher:
    def __init__(self, specs: Mapping[str, ProcessSpec],
                 on_sample: Callable[[ProcessSample, float], None],
                 poll: float = DEFAULT_POLL, clock: Callable[[], float] = time.monotonic) -> None:
        self.specs = dict(specs)
        self.on_sample = on_sample
        self.poll = poll
        self.clock = clock
        self._patterns = {n: re.compile(s.match) for n, s in self.specs.items() if s.match}
        self._tracked: dict[str, _Tracked] = {}
        self._wake = asyncio.Event()
        self._task: asyncio.Task[None] | None = None

    # -- control ---------------------------------------------------------------------------
    def start(self) -> None:
        if self._task is None:
            self._task = asyncio.get_running_loop().create_task(self._run(), name="watcher")

    async def close(self) -> None:
        if self._task is not None:
            self._task.cancel()
            with contextlib.suppress(asyncio.CancelledError):
                await self._task
            self._task = None
        for node in list(self._tracked):
            self._untrack(node)

    def track(self, node: str, pid: int) -> None:
        """The supervisor started ``node`` as ``pid`` (or a fixed pid is known): it runs, said
        at once. Not left to the next round: a process that ends before the loop gets there
        (a driver that exits at once while the loop is busy) would never have been seen
        running, and its run would be lost to whoever counts runs (``host.repair.crashloop``).
        A process already gone ran and ended: both are said, in that order."""
        self._untrack(node)
        self._emit(ProcessSample(node, True, pid))
        with contextlib.suppress(psutil.Error):
            self._adopt(node, psutil.Process(pid))
        if node not in self._tracked:  # gone, or a zombie not yet reaped
            self._emit(ProcessSample(node, False))
            return
        self._wake.set()

    def pid(self, node: str) -> int | None:
        """The pid of ``node``'s process as last found (None: not running, or not found yet)."""
        t = self._tracked.get(node)
        return None if t is None else t.proc.pid

    # -- the loop --------------------------------------------------------------------------
    async def _run(self) -> None:
        while True:
            self.sample()
            self._wake.clear()
            with contextlib.suppress(TimeoutError):  # not wait_for: it can swallow a cancel
                async with asyncio.timeout(self.poll):
                    await self._wake.wait()

    def sample(self) -> None:
        """One round: find missing processes, then sample every node once."""
        missing = [n for n in self.specs if n not in self._tracked]
        if missing:
            self._find(missing)
        for node in self.specs:
            self._emit(self._sample(node))

    def _find(self, missing: list[str]) -> None:
        for node in missing:
            pid = self.specs[node].pid
            if pid is not None:
                with contextlib.suppress(psutil.Error):
                    self._adopt(node, psutil.Process(pid))
        wanted = [n for n in missing if n in self._patterns and n not in self._tracked]
        if not wanted:
            return
        me = os.getpid()
        for proc in psutil.process_iter(["pid", "cmdline"]):
            cmdline = proc.info.get("cmdline") or []
            if proc.info["pid"] == me or not cmdline:
                continue
            line = " ".join(cmdline)
            for node in wanted:
                if node not in self._tracked and self._patterns[node].search(line):
                    with contextlib.suppress(psutil.Error):
                        self._adopt(node, proc)

    def _sample(self, node: str) -> ProcessSample:
        t = self._tracked.get(node)
        if t is None:
            return ProcessSample(node, False)
        try:
            with t.proc.oneshot():
                if t.proc.status() == psutil.STATUS_ZOMBIE:
                    raise psutil.NoSuchProcess(t.proc.pid)
                cpu = t.proc.cpu_percent(None)
                rss = t.proc.memory_info().rss
        except psutil.Error:
            self._untrack(node)
            return ProcessSample(node, False)
        return ProcessSample(node, True, t.proc.pid, cpu, rss)

    def _adopt(self, node: str, proc: psutil.Process) -> None:
        if proc.status() == psutil.STATUS_ZOMBIE:
            return
        t = self._tracked[node] = _Tracked(proc)
        try:
            t.fd = os.pidfd_open(proc.pid)
        except (AttributeError, OSError):
            return  # no pidfd: the exit is seen at the next poll
        asyncio.get_running_loop().add_reader(t.fd, self._exited, node)
        log.debug("tracking %s as pid %d", node, proc.pid)

    def _exited(self, node: str) -> None:
        self._untrack(node)
        self._emit(ProcessSample(node, False))
        self._wake.set()  # look for a replacement at once

    def _untrack(self, node: str) -> None:
        t = self._tracked.pop(node, None)
        if t is not None and t.fd is not None:
            asyncio.get_running_loop().remove_reader(t.fd)
            os.close(t.fd)

    def _emit(self, sample: ProcessSample) -> None:
        self.on_sample(sample, self.clock())
