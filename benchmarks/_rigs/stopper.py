"""``dxboard run --board URL`` as a real process, signalled and timed: how long its stop takes.

``StoppedRun.against(url, tmp)`` starts the daemon on a board URL (a hostile board, a real
emulator) as a ``host.launch.procs.Child``, waits until it printed its URLs (it is up, whatever
the board does), lets it meet the board for ``meet_s`` (so that the stop starts while the link
is being tried, failing or reconnecting), sends ``sig`` and returns the seconds from the
signal to the exit, the exit code and what it said. The daemon is killed (with its process
group) if it outlives ``give_up_s``, so nothing is left behind when a test fails.
``children(pid)`` and ``alive(pids)`` follow the processes it started.
"""

from __future__ import annotations

import contextlib
import os
import signal
import subprocess
import sys
import time
from dataclasses import dataclass, field
from pathlib import Path

from host.launch.ports import zenoh_endpoint
from host.launch.procs import Child
from host.launch.running import ROOT, TEDUSAR
from host.launch.waiting import wait_until


@dataclass
class StoppedRun:
    seconds: float  # from the signal to the exit
    code: int
    lines: list[str] = field(default_factory=list)  # stdout and stderr, interleaved
    children: list[int] = field(default_factory=list)  # its child pids before the signal

    @classmethod
    def against(cls, url: str, tmp: Path, key_hex: str = "ab" * 16, meet_s: float = 8.0,
                sig: int = signal.SIGTERM, give_up_s: float = 120.0,
                extra: tuple[str, ...] = ()) -> StoppedRun:
        argv = [sys.executable, "-m", "host.cli", "run", str(TEDUSAR),
                "--board", url, "--web", "127.0.0.1:0", "--journal", str(tmp / "j.sqlite"),
                "--zenoh", zenoh_endpoint(), *extra]
        env = {**os.environ, "PYTHONPATH": str(ROOT), "DXBOARD_KEY": key_hex}
        child = Child(argv, cwd=ROOT, env=env, merge_stderr=True, name="dxboard run")
        proc = child.proc
        try:
            try:
                up = child.wait_ready(lambda c: any(x.startswith("journal: ") for x in c.lines),
                                      give_up_s)
            except TimeoutError:
                raise AssertionError("dxboard run not up: "
                                     + "\n".join(child.lines[-20:])) from None
            if not up:
                raise AssertionError("dxboard run exited: " + "\n".join(child.lines[-20:]))
            end = time.monotonic() + meet_s
            wait_until(lambda: time.monotonic() >= end, meet_s + 60, "the board met")
            kids = children(proc.pid)
            t0 = time.monotonic()
            child.send(sig)
            try:
                code = proc.wait(give_up_s)
            except subprocess.TimeoutExpired:  # never stopped
                code = -999  # the caller's assertion says so
            seconds = time.monotonic() - t0
        finally:
            child.stop(signal.SIGKILL, 10, group=True)  # only if it still runs
        return cls(seconds, code, list(child.lines), kids)


def children(pid: int) -> list[int]:
    """The pids of ``pid``'s descendants now (from /proc, no library of ours)."""
    parent: dict[int, int] = {}
    for d in Path("/proc").iterdir():
        if d.name.isdigit():
            with contextlib.suppress(OSError, IndexError, ValueError):
                stat = (d / "stat").read_text()
                parent[int(d.name)] = int(stat.rsplit(")", 1)[1].split()[1])
    out, todo = [], [pid]
    while todo:
        p = todo.pop()
        kids = [c for c, pp in parent.items() if pp == p]
        out += kids
        todo += kids
    return out


def alive(pids: list[int]) -> list[int]:
    """Those of ``pids`` still running (zombies count as gone)."""
    out = []
    for p in pids:
        with contextlib.suppress(OSError, IndexError):
            state = Path(f"/proc/{p}/stat").read_text().rsplit(")", 1)[1].split()[0]
            if state != "Z":
                out.append(p)
    return out
