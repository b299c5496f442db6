"""Was a publisher starved? Its processes' time spent runnable but waiting for a CPU (Linux).

A topic that falls silent on a busy machine may be hung (its publisher sleeps, waiting for a
device that will not answer) or starved (its publisher is ready to run and waits on the run
queue behind other work). The frequency observer tells the two apart by this module: Linux
counts, for every thread, the nanoseconds it spent runnable but not running — the second field
of ``/proc/<pid>/task/<tid>/schedstat`` (kernel ``sched_info``, present since 2.6.x; it needs
``CONFIG_SCHED_INFO``, set by the common distributions). A hung publisher's count stands still;
a starved one's grows with the wall clock.

``run_queue_wait(pids)`` is that count, in seconds, summed over every thread of every pid given
(a chain: the node that publishes a topic and the process that feeds its device); ``None`` when
none of them could be read (no pid known, a process gone, another OS, another user's process
without access). ``WaitProbe`` is what the frequency observer holds: it reads the pids from a
lookup each time (a node restarted by the supervisor has a new pid) and keeps the count going
up across such changes, so the observer only takes differences. No clock here: the observer
bounds a difference by the wall time it passed in (several threads can wait at once).
"""

from __future__ import annotations

import logging
import os
import threading
from collections.abc import Callable, Iterable, Mapping

from host.diagnosis.model import SystemModel
from host.observers.silence import ChainState
from host.observers.topics import FrequencyObserver

log = logging.getLogger(__name__)

PROC = "/proc"


def _read_pid(pid: int, proc: str, skip: int | None) -> tuple[int, int] | None:
    """The run-queue wait of every thread of ``pid`` (ns) and how many are runnable now
    (thread ``skip``, the caller's own, left out of that count); None if unreadable."""
    tasks = os.path.join(proc, str(pid), "task")
    try:
        tids = os.listdir(tasks)
    except OSError:
        return None
    total, runnable, seen = 0, 0, False
    for tid in tids:
        try:
            with open(os.path.join(tasks, tid, "schedstat"), "rb") as f:
                fields = f.read().split()
            with open(os.path.join(tasks, tid, "stat"), "rb") as f:
                state = f.read().rpartition(b")")[2].split(None, 1)[:1]
        except OSError:
            continue  # a thread that ended meanwhile
        if len(fields) >= 2 and fields[1].isdigit():
            total += int(fields[1])
            seen = True
            if state == [b"R"] and tid != str(skip):
                runnable += 1
    return (total, runnable) if seen else None


def read_chain(pids: Iterable[int], proc: str = PROC, skip: int | None = None
               ) -> ChainState | None:
    """The run-queue wait (s) of every thread of ``pids``, summed, and how many of those
    threads are runnable now (running or waiting for a CPU; thread ``skip`` left out);
    None if no pid could be read (the caller falls back to judging without it).

    Linux adds a thread's wait to its count when the thread gets the CPU: a thread waiting
    right now shows only as runnable, its wait comes later."""
    total, runnable, seen = 0, 0, False
    for pid in pids:
        got = _read_pid(pid, proc, skip)
        if got is not None:
            total += got[0]
            runnable += got[1]
            seen = True
    return ChainState(total / 1e9, runnable) if seen else None


def run_queue_wait(pids: Iterable[int], proc: str = PROC) -> float | None:
    """Seconds the threads of ``pids`` spent runnable but waiting for a CPU, summed; None if
    no pid could be read."""
    state = read_chain(pids, proc)
    return None if state is None else state.wait


class WaitProbe:
    """The run-queue wait of a publisher chain whose pids ``lookup`` names (it may change).

    ``read()`` gives a running total in seconds that never goes backwards: when the chain's
    pids change (a restart) or a process ends (its threads' counts vanish), the total carries
    on from where it was rather than jumping; and the chain's threads runnable now (the
    calling thread left out: the daemon reads its own process too). None when nothing can
    be read.
    """

    def __init__(self, lookup: Callable[[], Iterable[int]], proc: str = PROC) -> None:
        self.lookup = lookup
        self.proc = proc
        self._pids: tuple[int, ...] = ()
        self._last: float | None = None  # the raw sum at the last read, for these pids
        self._total = 0.0

    def pids(self) -> tuple[int, ...]:
        return tuple(sorted(set(self.lookup())))

    def read(self) -> ChainState | None:
        pids = self.pids()
        raw = read_chain(pids, self.proc, threading.get_native_id()) if pids else None
        if raw is None:
            self._last = None
            return None
        if pids == self._pids and self._last is not None and raw.wait >= self._last:
            self._total += raw.wait - self._last
        elif pids != self._pids:
            log.debug("run-queue wait of pids %s (was %s)", pids, self._pids)
        self._pids, self._last = pids, raw.wait
        return ChainState(self._total, raw.runnable)

    def wait(self) -> float | None:
        """The running total alone."""
        got = self.read()
        return None if got is None else got.wait


def chain_of(model: SystemModel, topic: str) -> tuple[list[str], list[str]]:
    """The nodes and the devices ``topic``'s messages depend on: the nodes that publish it, and
    theirs for each input topic they publish it from (transitively), with those nodes'
    hardware."""
    nodes: list[str] = []
    devices: list[str] = []
    todo, seen = [topic], {topic}
    while todo:
        t = todo.pop()
        for c in model.components.values():
            if t not in c.publishes or c.name in nodes:
                continue
            nodes.append(c.name)
            devices += [h for h in c.hardware if h not in devices]
            for i in c.publishes[t]:
                if i not in seen:
                    seen.add(i)
                    todo.append(i)
    return nodes, devices


def wire_probes(observers: Iterable[object], model: SystemModel,
                node_pid: Callable[[str], int | None],
                device_pids: Mapping[str, int], way_in: Iterable[int] = ()
                ) -> dict[str, tuple[list[str], list[str]]]:
    """Give every frequency observer a ``WaitProbe`` over its topic's chain: the pids of its
    nodes (``node_pid``, asked at each reading: a restarted node has a new pid), of the
    processes that feed its devices (``device_pids``: the emulated board's, under
    ``--emulate``; empty for real devices) and ``way_in`` (the daemon's own: its middleware
    threads receive the messages). Returns what each observed topic was wired to."""
    way = list(way_in)
    wired: dict[str, tuple[list[str], list[str]]] = {}
    for o in observers:
        if not isinstance(o, FrequencyObserver):
            continue
        topic = o.topics[0]
        nodes, devices = chain_of(model, topic)
        fed = [d for d in devices if d in device_pids]
        if not nodes and not fed:
            continue  # nothing known: judged as before

        def lookup(nodes: list[str] = nodes, fed: list[str] = fed) -> list[int]:
            pids = way + [device_pids[d] for d in fed]
            return pids + [p for p in map(node_pid, nodes) if p is not None]

        o.probe = WaitProbe(lookup)
        wired[topic] = (nodes, fed)
    return wired
