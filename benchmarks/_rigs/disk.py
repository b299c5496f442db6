"""Issue 25 item 4 end to end: a real daemon repairs a lidar hang while its disk is full.

``full_disk_run(tmp)`` runs the fast virtual TEDUSAR robot under ``dxboard run --emulate``
(Zenoh: the lighter middleware) with its journal and node logs on a 3 MB tmpfs the run
mounts (``benchmarks._rigs.fulldisk``), and, once the robot is healthy: fills the disk and
waits until the daemon says so (``/api/status``: ``journal.problem``); injects ``hokuyo
hang`` and waits until the robot is healthy again after a power cycle of the lidar that
started after the fault (while the disk is still full); frees the space and waits until every
entry the daemon had recorded by then (``dxboard_journal_recorded_entries_total`` on
``/metrics``; ids come without gaps) is in the journal file; stops the daemon with SIGINT and
counts the entries the daemon said it recorded that are not in the journal. The test
(tests/daemon/test_full_disk.py) asserts on the ``FullDiskRun`` it returns, and
``benchmarks/disk.py`` reports its times.
"""

from __future__ import annotations

import re
import time
import urllib.request
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from benchmarks._rigs.fulldisk import small_disk
from benchmarks._rigs.robots import fast_copy, key_file
from host.launch.running import MIN_WAIT_S, RunningDaemon, healthy
from host.launch.waiting import wait_until

HEAL_S = 120.0


@dataclass
class FullDiskRun:
    fault_to_healthy_s: float = 0.0  # hokuyo hang -> healthy, the disk full all along
    free_to_journalled_s: float = 0.0  # space back -> every entry recorded by then on disk
    held_at_free: int = 0  # entries the daemon held in memory when the space returned
    recorded: int = 0  # entries the daemon said it recorded (the last /metrics before stop)
    lost: int = 0  # of those, not in the journal after the stop
    dropped: int = 0  # what the daemon itself counted as dropped
    full_status: dict[str, Any] = field(default_factory=dict)  # /api/status, disk full
    repaired: list[dict[str, Any]] = field(default_factory=list)  # the repairs of the hang
    stderr: str = ""  # what the daemon said on its terminal
    exit_code: int | None = None
    node_logs: list[str] = field(default_factory=list)  # the files under the logs folder


def metric(d: RunningDaemon, name: str) -> float:
    """One sample of the daemon's ``/metrics`` (the series labelled robot and site only)."""
    with urllib.request.urlopen(d.urls["web"] + "metrics", timeout=30) as r:
        text = r.read().decode()
    m = re.search(rf"^{name}{{[^}}]*}} ([0-9.e+]+)$", text, re.M)
    if m is None:
        raise AssertionError(f"no {name} in /metrics")
    return float(m.group(1))


def _ids(d: RunningDaemon) -> set[int]:
    return {e.id for e in d.journal()}


def full_disk_run(tmp: Path) -> FullDiskRun:
    out = FullDiskRun()
    key = key_file(tmp)
    with small_disk(tmp / "disk", "3m") as disk:
        d = RunningDaemon(tmp, fast_copy(tmp), journal_dir=disk.path, extra_args=(
            "--key-file", str(key), "--middleware", "zenoh"))
        try:
            d.wait_for(healthy, HEAL_S, "the robot powered up and healthy")
            disk.fill()
            out.full_status = d.wait_for(lambda s: s["journal"]["problem"] == "disk full",
                                         MIN_WAIT_S, "the daemon to say its disk is full")
            fault_wall = time.time()
            fault = time.monotonic()
            d.inject("hokuyo", "hang")

            def repaired(s: dict[str, Any]) -> bool:
                cycles = [r for r in s["repairs"] if r["action"] == "power_cycle"
                          and r["args"] == ["hokuyo"] and (r["started"] or 0) >= fault_wall]
                return healthy(s) and any(r["state"] == "succeeded" for r in cycles)

            st = d.wait_for(repaired, HEAL_S, "healthy again after the hang, disk full")
            out.fault_to_healthy_s = time.monotonic() - fault
            out.repaired = [r for r in st["repairs"] if (r["started"] or 0) >= fault_wall]
            still = d.status()["journal"]
            assert still["problem"] == "disk full", f"the disk was freed meanwhile: {still}"
            out.held_at_free = int(still["held"])
            recorded = int(metric(d, "dxboard_journal_recorded_entries_total"))
            freed = time.monotonic()
            disk.free()
            wait_until(lambda: set(range(1, recorded + 1)) <= _ids(d), MIN_WAIT_S,
                       f"the {recorded} entries recorded before the space returned on disk",
                       interval=0.05)
            out.free_to_journalled_s = time.monotonic() - freed
            d.wait_for(lambda s: s["journal"]["problem"] == "", MIN_WAIT_S,
                       "the daemon to say its journal writes again")
            out.recorded = int(metric(d, "dxboard_journal_recorded_entries_total"))
            out.dropped = int(metric(d, "dxboard_journal_dropped_entries_total"))
            out.exit_code = d.interrupt()
            out.lost = len(set(range(1, out.recorded + 1)) - _ids(d))
            out.node_logs = sorted(p.name for p in (disk.path / "journal-logs").iterdir())
        finally:
            d.close()
            out.stderr = d.err_path.read_text()
    return out
