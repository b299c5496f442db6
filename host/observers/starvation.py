"""Was a publisher starved? Its processes' time spent runnable but waiting for a CPU (Linux).

A topic that falls silent on a busy machine may be hung (its publisher sleeps, waiting for a
device that will not answer) or starved (its publisher is ready to run and waits on the run
queue behind other work). The frequency observer tells the two apart by this module: Linux
counts, for every thread, the nanoseconds it spent runnable but not running — the second field
of ``/proc/<pid>/task/<tid>/schedstat`` (kernel ``sched_info``, present since 2.6.x; it needs
``CONFIG_SCHED_INFO``, set by the common distributions). A hung publisher's count stands still;
a starved one's grows with the wall clock.

``read_threads(pids)`` reads those counts for every thread of every pid given (a chain: the
nodes a topic depends on, the process that feeds their devices, the daemon itself);
``run_queue_wait(pids)`` sums them. ``WaitProbe`` is what the frequency observer holds: it
reads the pids from a lookup each time (a node restarted by the supervisor has a new pid) and
says, reading after reading, how long the chain's most starved thread waited and which threads
are stuck on the run queue right now; None when nothing can be read (no pid known, a process
gone, another OS, another user's process without access), and the observer judges without it.
No clock here: the observer bounds a wait by the wall time it passed in.
"""

from __future__ import annotations

import logging
import os
import threading
from collections.abc import Callable, Iterable, Mapping
from typing import NamedTuple

from host.diagnosis.model import SystemModel
from host.observers.silence import ChainState
from host.observers.topics import FrequencyObserver

log = logging.getLogger(__name__)

PROC = "/proc"


class Thread(NamedTuple):
    """One thread's scheduler counts (``schedstat``: ns on a CPU, ns waiting for one, times it
    got one) and whether it is runnable now (``stat`` state R: running or waiting)."""

    cpu_ns: int
    wait_ns: int
    slices: int
    runnable: bool


def read_threads(pids: Iterable[int], proc: str = PROC) -> dict[tuple[int, int], Thread]:
    """Every thread of ``pids`` that could be read, by (pid, tid); empty if none could."""
    out: dict[tuple[int, int], Thread] = {}
    for pid in pids:
        tasks = os.path.join(proc, str(pid), "task")
        try:
            tids = os.listdir(tasks)
        except OSError:
            continue  # gone, or not ours to read
        for tid in tids:
            try:
                with open(os.path.join(tasks, tid, "schedstat"), "rb") as f:
                    fields = f.read().split()
                with open(os.path.join(tasks, tid, "stat"), "rb") as f:
                    state = f.read().rpartition(b")")[2].split(None, 1)[:1]
            except OSError:
                continue  # a thread that ended meanwhile
            if len(fields) >= 3 and all(x.isdigit() for x in fields[:3]) and tid.isdigit():
                out[pid, int(tid)] = Thread(int(fields[0]), int(fields[1]), int(fields[2]),
                                            state == [b"R"])
    return out


def run_queue_wait(pids: Iterable[int], proc: str = PROC) -> float | None:
    """Seconds the threads of ``pids`` spent runnable but waiting for a CPU, summed; None if
    no pid could be read."""
    threads = read_threads(pids, proc)
    return sum(t.wait_ns for t in threads.values()) / 1e9 if threads else None


class WaitProbe:
    """How starved a publisher chain is, the chain's pids named by ``lookup`` (it may change).

    ``read()`` compares each thread with the previous reading. The chain's wait grows by the
    *most* any one thread waited in between (the publishing path is as late as its most
    starved thread; a sum over dozens of threads that each waited a little would call a busy
    but healthy chain starved), so it is a running total that never goes backwards, across
    restarts (new pids) too. Linux adds a thread's wait to its count only when the thread gets
    the CPU, so a thread runnable at both readings that got no CPU in between (same CPU time,
    same count of times it ran) is *stuck* on the run queue: ``ChainState.stuck`` counts those
    (the calling thread left out: it is running as it reads, though its wait counts like any
    other's — the daemon reads its own process too, and its loop thread held up on the run queue
    holds up every message behind it). None when nothing can be read.
    """

    def __init__(self, lookup: Callable[[], Iterable[int]], proc: str = PROC) -> None:
        self.lookup = lookup
        self.proc = proc
        self._threads: dict[tuple[int, int], Thread] = {}
        self._total = 0.0

    def pids(self) -> tuple[int, ...]:
        return tuple(sorted(set(self.lookup())))

    def read(self) -> ChainState | None:
        pids = self.pids()
        threads = read_threads(pids, self.proc) if pids else {}
        if not threads:
            self._threads = {}
            return None
        me = (os.getpid(), threading.get_native_id())
        worst, stuck = 0, 0
        for key, t in threads.items():
            old = self._threads.get(key)
            if old is None:
                continue
            worst = max(worst, t.wait_ns - old.wait_ns)  # the reader's own wait counts too
            if key != me and t.runnable and old.runnable \
                    and (t.cpu_ns, t.slices) == (old.cpu_ns, old.slices):
                stuck += 1
        self._threads = threads
        self._total += worst / 1e9
        return ChainState(self._total, stuck)

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
    threads receive the messages). While none of the publisher's side is known (its node not
    found yet, no emulated device) the probe reads nothing and the topic is judged as
    without it. Returns what each observed topic was wired to."""
    way = list(way_in)
    wired: dict[str, tuple[list[str], list[str]]] = {}
    for o in observers:
        if not isinstance(o, FrequencyObserver) or not o.own_time:
            continue
        topic = o.topics[0]
        nodes, devices = chain_of(model, topic)
        fed = [d for d in devices if d in device_pids]
        if not nodes and not fed:
            continue  # nothing known: judged as before

        def lookup(nodes: list[str] = nodes, fed: list[str] = fed) -> list[int]:
            side = [device_pids[d] for d in fed]
            side += [p for p in map(node_pid, nodes) if p is not None]
            return way + side if side else []  # the way in alone says nothing of a publisher

        o.probe = WaitProbe(lookup)
        wired[topic] = (nodes, fed)
    return wired
