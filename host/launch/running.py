"""``dxboard run`` as a child process, driven as a person would: for the tests and benchmarks.

``RunningDaemon(tmp, system_dir, ...)`` starts ``dxboard run SYSTEM --emulate`` (or ``--board
URL``) as a ``host.launch.procs.Child`` on free ports (web on port 0, zenoh from
``host.launch.ports``; a zenoh port taken meanwhile by another process is retried on a fresh
one) with a journal in ``tmp``, waits until it printed every URL (the ``journal:`` line comes
last), and offers what a person would use: the JSON API (``status()``, ``wait_for()``),
``dxboard inject`` on the printed control URL, ``dxboard board``/``quarantine``/``hold``, the
journal, SIGINT (``interrupt()``, ``ctrl_c()`` to its whole group as a terminal does), ``kill
-9``; ``close()`` stops it as a person would, and kills it only if it hangs. Its waits poll
until generous deadlines (``MIN_WAIT_S`` at least, ``host.launch.waiting``): a busy machine
is slow, and a deadline only bounds how long a broken run takes to fail. ``healthy(status)``
says the robot is up and well; ``key_file(tmp, key)`` writes a key as ``--key-file`` wants it;
``healthy_robot(tmp, system, key)`` is a daemon once its robot is healthy, stopped afterwards.
Questions about a run: ``node_processes`` (the virtual robot's node processes),
``last_id`` (a mark in the journal), ``actions_started`` (the repair actions since a mark).
"""

from __future__ import annotations

import contextlib
import json
import os
import signal
import subprocess
import sys
import time
import urllib.request
from collections.abc import Callable, Iterator, Mapping
from pathlib import Path
from typing import Any

import psutil

from host.events import ActionRecord, ActionState
from host.journal import Entry, JournalReader
from host.launch.ports import clashed, zenoh_endpoint
from host.launch.procs import Child
from host.launch.waiting import wait_until

ROOT = Path(__file__).resolve().parents[2]
TEDUSAR = ROOT / "models" / "tedusar"
MIN_WAIT_S = 60.0  # the shortest deadline of a wait on the daemon, on a busy machine
START_S = 300.0  # bounds a start that hangs; a working one prints its URLs long before
CLOSE_GRACE_S = 20.0  # SIGINT, then SIGKILL


def _has_journal(child: Child) -> bool:
    return "journal" in child.urls()


class RunningDaemon:
    def __init__(self, tmp: Path, system_dir: Path = TEDUSAR,
                 extra_args: tuple[str, ...] = (), zenoh: str | None = None,
                 env: Mapping[str, str] | None = None, journal_dir: Path | None = None,
                 board: str | None = None) -> None:
        """``zenoh``: the topic endpoint to use (a restarted daemon takes its predecessor's,
        where the nodes it left behind reconnect); default: a fresh one. ``env``: variables
        to set for it (and the nodes it starts), e.g. a ROS 2 domain of its own.
        ``journal_dir``: where the journal and the node logs go (default ``tmp``; a small
        disk of its own, ``benchmarks._rigs.fulldisk``). ``board``: the URL of a board that runs
        on its own (``--board``; default ``--emulate``, a board that dies with the daemon)."""
        self.env = {**os.environ, **(env or {})}
        self.system_dir = system_dir
        self.journal_path = (journal_dir or tmp) / "journal.sqlite"
        # its zenoh endpoint's credentials (host.observers.sources.zenoh_auth: beside the
        # journal), for a peer of the robot's topics of one's own
        self.auth = self.journal_path.parent / "journal-zenoh.auth"
        self.err_path = tmp / "daemon.err"
        for _ in range(5):  # its zenoh port taken by another process meanwhile: a fresh one
            self.zenoh = zenoh or zenoh_endpoint()
            where = ["--emulate"] if board is None else ["--board", board]
            argv = [sys.executable, "-m", "host.cli", "run", str(system_dir), *where,
                    "--web", "127.0.0.1:0", "--journal", str(self.journal_path),
                    "--zenoh", self.zenoh, *extra_args]
            # a process group of its own, as a shell gives a command it runs: Ctrl-C on a
            # terminal signals the whole group (``ctrl_c``)
            self.child = Child(argv, env=self.env, cwd=ROOT, stderr=self.err_path,
                               name="dxboard run")
            if self.child.wait_ready(_has_journal, START_S):
                break
            self.child.stop()
            if zenoh or not clashed(self.err_path.read_text()):
                break
        self.urls: dict[str, str] = self.child.urls()
        if "journal" not in self.urls:
            raise AssertionError("dxboard run exited: " + self.err_path.read_text()[-2000:])
        # what it says after its URL lines (the last is the journal's) is ``lines``: counted
        # from that line, not from what the reader had read by now (on a busy machine the
        # run's first line is read before this thread gets here)
        said = list(self.child.lines)
        self._told = next(i + 1 for i in range(len(said) - 1, -1, -1)
                          if said[i].strip().startswith("journal: "))

    @property
    def proc(self) -> subprocess.Popen[bytes]:
        return self.child.proc

    @property
    def lines(self) -> list[str]:
        """What it said on its terminal after the URLs, read as it comes."""
        return self.child.lines[self._told:]

    def status(self) -> dict[str, Any]:
        """``/api/status``, asked again (each read waiting up to 30 s) until MIN_WAIT_S: a
        daemon busy on a loaded machine answers late, which is not what a caller asserts."""
        failures: list[str] = []

        def read() -> dict[str, Any] | None:
            try:
                with urllib.request.urlopen(self.urls["web"] + "api/status", timeout=30) as r:
                    data: dict[str, Any] = json.load(r)
                return data
            except (OSError, ValueError) as exc:  # URLError, a timeout, a cut-off answer
                failures.append(repr(exc))
                if self.proc.poll() is not None:
                    raise AssertionError("dxboard run exited: "
                                         + self.err_path.read_text()[-2000:]) from exc
                return None

        return wait_until(read, MIN_WAIT_S, "an answer from /api/status", interval=0.5,
                          show=lambda: failures[-3:])

    def wait_for(self, what: Callable[[dict[str, Any]], bool], timeout: float = 20.0,
                 label: str = "") -> dict[str, Any]:
        """The status once ``what(status)`` holds (polled, up to ``timeout`` s, at least
        MIN_WAIT_S: a deadline only bounds how long a broken run takes to fail)."""
        last: list[dict[str, Any]] = []

        def probe() -> dict[str, Any] | None:
            last[:] = [self.status()]
            return last[0] if what(last[0]) else None

        return wait_until(probe, max(timeout, MIN_WAIT_S), label or "the daemon's status",
                          interval=0.1,
                          show=lambda: {k: last[0][k] for k in ("diagnoses", "repairs")})

    def wait_journal(self, what: Callable[[], object], timeout: float, label: str) -> None:
        """Wait until ``what()`` (a question about the journal) holds (at least MIN_WAIT_S)."""
        wait_until(what, max(timeout, MIN_WAIT_S), label, interval=0.3,
                   show=lambda: {k: self.status()[k] for k in ("diagnoses", "repairs")})

    def caught_up(self) -> None:
        """Wait until the journal holds everything the daemon recorded until now: its writer
        commits in the background, so the status can be ahead of it. The daemon stamps entries
        with the machine's CLOCK_MONOTONIC (a current summary every second), so an entry
        stamped after now proves that every earlier one is committed."""
        now = time.monotonic()
        wait_until(lambda: max((e.mono for e in self.journal()), default=0.0) >= now,
                   MIN_WAIT_S, "the journal to catch up", interval=0.3)

    def settled(self, seconds: float, runs: int = 2) -> None:
        """Let the daemon have its chance: wait until it ran ``runs`` more diagnoses (a safety
        tick comes at least every 2 s) and ``seconds`` passed, however slow the machine. For
        callers that then assert that something did *not* happen."""
        end = time.monotonic() + seconds
        start = self.diagnosis_runs()
        wait_until(lambda: time.monotonic() >= end and self.diagnosis_runs() >= start + runs,
                   seconds + MIN_WAIT_S, f"{runs} more diagnoses and {seconds} s",
                   interval=0.2, show=self.diagnosis_runs)

    def diagnosis_runs(self) -> int:
        return int(self.status()["counters"]["diagnosis_runs"])

    def inject(self, *args: str) -> None:
        subprocess.run([sys.executable, "-m", "host.cli", "inject", self.urls["control"],
                        *args], check=True, cwd=ROOT, capture_output=True, timeout=MIN_WAIT_S)

    def journal(self, kind: str | tuple[str, ...] | None = None) -> list[Entry]:
        return JournalReader(self.journal_path).query(kind=kind, limit=100000)

    def board(self, *args: str, key_file: Path) -> str:
        """``dxboard board BOARD_URL ARGS`` with the key file, as an operator would."""
        out = subprocess.run([sys.executable, "-m", "host.cli", "board", self.urls["board"],
                              *args, "--key-file", str(key_file)], check=True, cwd=ROOT,
                             capture_output=True, text=True, timeout=MIN_WAIT_S)
        return out.stdout

    def operator(self, command: str, *args: str) -> str:
        """``dxboard quarantine|hold ARGS`` against this daemon, as its operator would."""
        out = subprocess.run([sys.executable, "-m", "host.cli", command, *args, "--operator",
                              self.urls["operator"]], check=True, cwd=ROOT,
                             capture_output=True, text=True, timeout=60)
        return out.stdout.strip()

    def kill(self) -> None:
        """``kill -9`` the daemon: no clean-up of any kind."""
        self.proc.kill()
        self.proc.wait(10)

    def ctrl_c(self, timeout: float = MIN_WAIT_S) -> int:
        """Ctrl-C on its terminal: SIGINT to its whole process group; its exit code."""
        self.child.send(signal.SIGINT, group=True)
        return self.proc.wait(timeout)

    def interrupt(self, timeout: float = MIN_WAIT_S) -> int:
        """Ctrl-C; its exit code (a stop takes about 2 s on a quiet machine, over 20 s in a
        suite run nice'd beside CPU hogs). A daemon still running ``timeout`` s later is a
        failure (AssertionError) with what it said on stderr (what its stop waits for,
        ``host.launch.stopping``) and where each of its threads is (SIGUSR1)."""
        self.proc.send_signal(signal.SIGINT)
        try:
            return self.proc.wait(timeout)
        except subprocess.TimeoutExpired:
            self.proc.send_signal(signal.SIGUSR1)
            with contextlib.suppress(AssertionError):
                wait_until(lambda: "most recent call first" in self.err_path.read_text(), 10,
                           "the daemon's stacks")
            raise AssertionError(f"dxboard run did not stop {timeout:g} s after SIGINT:\n"
                                 + self.err_path.read_text()[-8000:]) from None

    def close(self) -> None:
        """Stop it as a person would (SIGINT); kill it only if it hangs. Idempotent."""
        self.child.stop(signal.SIGINT, CLOSE_GRACE_S)


def key_file(tmp: Path, key: bytes) -> Path:
    """A key file as ``--key-file`` wants it (hex, readable by its owner only)."""
    path = tmp / "key"
    path.write_text(key.hex())
    path.chmod(0o600)
    return path


def healthy(s: dict[str, Any]) -> bool:
    """The robot is up: board link up, nothing diagnosed, and every repair action finished."""
    return bool(s["board_link_up"]) and not s["diagnoses"] and bool(s["repairs"]) and all(
        r["state"] in ("succeeded", "failed", "timeout") for r in s["repairs"])


@contextlib.contextmanager
def healthy_robot(tmp: Path, system_dir: Path, key: bytes,
                  heal_s: float = 90.0) -> Iterator[RunningDaemon]:
    """``dxboard run SYSTEM --emulate`` with a key file, once it has powered up and is healthy
    (a shared daemon of many questions); stopped afterwards."""
    d = RunningDaemon(tmp, system_dir, extra_args=("--key-file", str(key_file(tmp, key))))
    try:
        d.wait_for(healthy, heal_s, "the robot powered up and healthy")
        yield d
    finally:
        d.close()


def node_processes(robot: Path) -> dict[str, list[int]]:
    """The virtual robot's node processes of this robot directory, by node."""
    out: dict[str, list[int]] = {}
    for p in psutil.process_iter(["pid", "cmdline"]):
        try:
            cmd = p.info["cmdline"] or []
            if "emulator.robot.node" not in cmd or p.status() == psutil.STATUS_ZOMBIE:
                continue
            if p.environ().get("DXBOARD_ROBOT") != str(robot.resolve()):
                continue
        except psutil.Error:
            continue
        out.setdefault(cmd[cmd.index("emulator.robot.node") + 1], []).append(p.info["pid"])
    return out


def last_id(d: RunningDaemon) -> int:
    """The journal's last entry once it holds everything recorded until now (a mark)."""
    d.caught_up()
    return max((e.id for e in d.journal()), default=0)


def actions_started(d: RunningDaemon, after: int) -> list[str]:
    """The repair actions (``power_cycle(hokuyo)``) started since the journal entry ``after``."""
    return [f"{p.action}({','.join(p.args)})" for e in d.journal("action") if e.id > after
            for p in [e.payload] if isinstance(p, ActionRecord)
            and p.state == ActionState.STARTED]
