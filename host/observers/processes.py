"""Process observers: a node runs (NObs) and its CPU and memory stay within limits (PObs).

Both read ``ProcessSample`` values, produced by ``host.observers.watcher.ProcessWatcher`` from
the real processes (or by the daemon's supervisor for processes it starts). ``NodeObserver``
emits ``running(n)`` / ``¬running(n)``. ``PropertyObserver`` emits ``ok(n/cpu)`` iff the
node's CPU use (percent of one core, averaged since the previous sample) is at most
``cpu_percent``, and ``ok(n/memory)`` iff its resident memory is at most ``memory_mb``; while
the node does not run both are retracted (a stopped process has no CPU use to judge).

Detection latency: an exit of a watched process is seen at once (Linux pidfd, in the
watcher), a start at the watcher's next scan (``poll``, 0.5 s by default); CPU and memory at
the next sample (every ``poll``). With no sample for ``validity`` seconds (a dead watcher)
the literals are retracted.
"""

from __future__ import annotations

from dataclasses import dataclass

import host.atoms as A
from host.observers.base import DEFAULT_REFRESH, DEFAULT_VALIDITY, Observer

#: how often the watcher looks for processes and samples them, seconds
DEFAULT_POLL = 0.5


@dataclass(frozen=True)
class ProcessSpec:
    """How to find node ``node``'s process: a fixed ``pid``, a command-line ``match``, or
    ``supervised`` (the pid comes through ``ProcessWatcher.track``). Here, beside the
    samples, not in the watcher: reading the observers' section needs neither psutil nor
    asyncio."""

    node: str
    pid: int | None = None
    match: str | None = None
    supervised: bool = False


@dataclass(frozen=True)
class ProcessSample:
    """What the watcher saw of node ``node`` at one moment."""

    node: str
    running: bool
    pid: int | None = None
    cpu_percent: float | None = None  # of one core, since the previous sample
    rss_bytes: int | None = None


class ProcessObserver(Observer[ProcessSample]):
    """An observer fed with the samples of one node."""

    node: str = ""


class NodeObserver(ProcessObserver):
    kind = "node"

    def __init__(self, node: str, *, name: str | None = None,
                 validity: float = DEFAULT_VALIDITY, refresh: float = DEFAULT_REFRESH) -> None:
        super().__init__(name or f"node:{node}", validity, refresh)
        self.node = node
        self.atom = str(A.running(node))

    def atoms(self) -> list[str]:
        return [self.atom]

    def _feed(self, item: ProcessSample, now: float) -> None:
        self._say(self.atom, item.running, now)


class PropertyObserver(ProcessObserver):
    kind = "property"

    def __init__(self, node: str, cpu_percent: float | None = None,
                 memory_mb: float | None = None, *, name: str | None = None,
                 validity: float = DEFAULT_VALIDITY, refresh: float = DEFAULT_REFRESH) -> None:
        super().__init__(name or f"property:{node}", validity, refresh)
        if cpu_percent is None and memory_mb is None:
            raise ValueError(f"{self.name}: give cpu_percent, memory_mb or both")
        self.node = node
        self.cpu_percent = cpu_percent
        self.memory_mb = memory_mb
        self.cpu_atom = str(A.ok(f"{node}/cpu"))
        self.memory_atom = str(A.ok(f"{node}/memory"))

    def atoms(self) -> list[str]:
        return ([self.cpu_atom] if self.cpu_percent is not None else []) + (
            [self.memory_atom] if self.memory_mb is not None else [])

    def _feed(self, item: ProcessSample, now: float) -> None:
        if not item.running:
            for atom in self.atoms():
                self._forget(atom, now)
            return
        if self.cpu_percent is not None and item.cpu_percent is not None:
            self._say(self.cpu_atom, item.cpu_percent <= self.cpu_percent, now)
        if self.memory_mb is not None and item.rss_bytes is not None:
            self._say(self.memory_atom, item.rss_bytes <= self.memory_mb * 1e6, now)
