"""Starting and stopping nodes: processes the host supervises itself, and systemd units.

``ProcessSupervisor(configs, log_dir)`` is the actuator behind ``start_node``/``stop_node``
(configured by ``processes:`` in ``system.yaml``, see ``host.repair.processes``):

- a ``command`` node runs as an asyncio subprocess in its own session (process group), its
  stdout and stderr appended to ``log_dir/<node>.log`` with a header line per start and a
  footer line with the exit status (rotated, and never failing a start or stop on a full disk:
  ``host.repair.nodelog``); ``stop`` sends SIGTERM to the whole group, then SIGKILL
  after the node's ``stop_timeout_s``, and waits for the exit (no zombies, no stray children).
  A reaper task per process notes an exit the host did not ask for; ``pid(node)`` is the live
  pid, and ``on_start(node, pid)`` is called after every start so the daemon can hand it to the
  observers (``hub.watcher.track(node, pid)``);
- a ``systemd`` node runs ``systemctl start UNIT`` / ``systemctl stop UNIT`` (``systemctl``
  looked up on ``PATH``; ``--user`` with ``user=True``) and asks ``systemctl show -p MainPID
  --value UNIT`` for its pid, for the same hand-over. A non-zero exit of systemctl is a
  ``ProcessError`` carrying its output.

``start`` of a node that runs already returns its pid without starting a second copy; ``stop``
of a node that does not run is a no-op. ``close()`` stops every process it started.

Nodes die with the daemon, even one killed with SIGKILL (``host.lifeline``: no orphan keeps
running unsupervised; under systemd the unit's control group would end them anyway). They run
in their own sessions (so a terminal's Ctrl-C reaches the daemon alone, which stops them in
order), and the supervisor keeps a record of
what it runs (``log_dir/nodes.json``: pid, start time, command line and a digest of the
environment it gave), and ``adopt()``, called by the next daemon before it repairs anything,
takes over every recorded node that still runs the same command with the same environment
(``start`` then returns its pid instead of starting a second copy; ``stop`` stops it) and stops
the ones that do not match (a node wired to a board or devices that are gone).
"""

from __future__ import annotations

import asyncio
import contextlib
import hashlib
import json
import logging
import os
import signal
import time
from collections.abc import Callable, Mapping
from pathlib import Path
from typing import IO

import psutil

from host.errors import RemoteError
from host.lifeline import lifeline
from host.repair import nodelog
from host.repair.nodelog import DEFAULT_MAX_BYTES, NodeLogs
from host.repair.processes import ProcessConfig

log = logging.getLogger(__name__)

OnStart = Callable[[str, int], None]


class ProcessError(RemoteError):
    """A node could not be started or stopped (no configuration, exec failed, systemctl)."""


RECORD = "nodes.json"
ADOPT_POLL_S = 0.2


class _Running:
    """A node's process: one this supervisor started (``proc``) or one it adopted (``pid``)."""

    def __init__(self, pid: int, logf: IO[bytes],
                 proc: asyncio.subprocess.Process | None = None) -> None:
        self.pid = pid
        self.proc = proc
        self.logf = logf
        self.stopping = False
        self.code: int | None = None  # exit status once it exited (adopted: -1, unknown)
        self.exited = asyncio.Event()
        self.reaper: asyncio.Task[None] | None = None

    async def wait(self) -> int:
        """Until it exits: its status (an adopted process's is unknown: -1)."""
        if self.proc is not None:
            return await self.proc.wait()
        try:
            p = psutil.Process(self.pid)
            while p.is_running() and p.status() != psutil.STATUS_ZOMBIE:
                await asyncio.sleep(ADOPT_POLL_S)
        except psutil.Error:
            pass
        return -1


class ProcessSupervisor:
    def __init__(self, configs: Mapping[str, ProcessConfig], log_dir: str | Path, *,
                 on_start: OnStart | None = None, user: bool = False,
                 systemctl: str = "systemctl", env: Mapping[str, str] | None = None,
                 log_max_bytes: int = DEFAULT_MAX_BYTES) -> None:
        self.configs = dict(configs)
        self.env = dict(env or {})  # for every process, under each one's own env
        self.log_dir = Path(log_dir)
        self.logs = NodeLogs(self.log_dir, log_max_bytes)
        self.on_start = on_start
        self.user = user
        self.systemctl = systemctl
        self.exits: dict[str, int] = {}  # node -> last exit status (negative: signal)
        self._running: dict[str, _Running] = {}
        self._units: dict[str, int | None] = {}  # systemd node -> pid at its last start

    def config(self, node: str) -> ProcessConfig:
        cfg = self.configs.get(node)
        if cfg is None:
            raise ProcessError(f"node {node} has no entry under processes: in system.yaml")
        return cfg

    def pid(self, node: str) -> int | None:
        r = self._running.get(node)
        if r is not None and r.code is None:
            return r.pid
        return self._units.get(node)

    def log_file(self, node: str) -> Path:
        return self.logs.path(node)

    # -- start / stop ----------------------------------------------------------------------
    async def start(self, node: str) -> int | None:
        """Start ``node``; its pid (None for a unit whose pid systemd does not tell)."""
        cfg = self.config(node)
        if cfg.unit is not None:
            await self._systemctl("start", cfg.unit)
            pid = await self._main_pid(cfg.unit)
            self._units[node] = pid
        else:
            pid = await self._spawn(cfg)
        if pid is not None and self.on_start is not None:
            self.on_start(node, pid)
        return pid

    async def stop(self, node: str) -> int | None:
        """Stop ``node``; its exit status (None for a unit, or when it was not running)."""
        cfg = self.config(node)
        if cfg.unit is not None:
            await self._systemctl("stop", cfg.unit)
            self._units[node] = None
            return None
        r = self._running.get(node)
        if r is None or r.code is not None:
            return None
        r.stopping = True
        self._signal(r.pid, signal.SIGTERM)
        try:
            await asyncio.wait_for(r.exited.wait(), cfg.stop_timeout_s)
        except TimeoutError:
            log.warning("%s did not stop within %g s of SIGTERM: SIGKILL", node,
                        cfg.stop_timeout_s)
            self._signal(r.pid, signal.SIGKILL)
            await r.exited.wait()
        self._signal(r.pid, signal.SIGKILL)  # children that outlived the leader
        if r.reaper is not None:
            await r.reaper
        return r.code

    def kill_all(self) -> None:
        """SIGKILL every process this supervisor started, with its process group, at once (a
        stop that ran out of time)."""
        for node, r in list(self._running.items()):
            if r.code is None:
                log.warning("%s (pid %d): SIGKILL, the stop ran out of time", node, r.pid)
                r.stopping = True
                self._signal(r.pid, signal.SIGKILL)

    async def close(self) -> None:
        """Stop every process this supervisor started (units are left to systemd), all at
        once: one after the other, nine nodes on a loaded machine took longer than a person
        waits for Ctrl-C (over 20 s)."""
        await asyncio.gather(*(self.stop(node) for node in list(self._running)))

    # -- processes the host runs -----------------------------------------------------------
    async def _spawn(self, cfg: ProcessConfig) -> int:
        node = cfg.node
        r = self._running.get(node)
        if r is not None and r.code is None:
            return r.pid
        stamp = time.strftime("%Y-%m-%d %H:%M:%S")
        logf = self.logs.open(node, f"--- {stamp} start: {' '.join(cfg.argv)}\n")
        try:
            proc = await asyncio.create_subprocess_exec(
                *cfg.argv, stdin=asyncio.subprocess.DEVNULL, stdout=logf,
                stderr=asyncio.subprocess.STDOUT, cwd=cfg.cwd,
                env={**os.environ, **self.env, **cfg.env}, start_new_session=True,
                preexec_fn=lifeline())  # dies with the daemon, even a killed one
        except OSError as exc:
            nodelog.write(logf, f"--- cannot start: {exc}\n")
            nodelog.close(logf)
            raise ProcessError(f"cannot start {node}: {exc.strerror or exc} ({cfg.argv[0]})"
                               ) from exc
        self._watch(node, _Running(proc.pid, logf, proc))
        self._record_write()
        log.info("started %s as pid %d", node, proc.pid)
        return proc.pid

    def _watch(self, node: str, r: _Running) -> None:
        self._running[node] = r
        r.reaper = asyncio.get_running_loop().create_task(self._reap(node, r),
                                                           name=f"reap:{node}")

    async def _reap(self, node: str, r: _Running) -> None:
        code = r.code = await r.wait()
        r.exited.set()
        self.exits[node] = code
        how = ("an unknown status" if r.proc is None else
               f"signal {-code}" if code < 0 else f"status {code}")
        nodelog.write(r.logf, f"--- exited with {how}{' (stopped)' if r.stopping else ''}\n")
        nodelog.close(r.logf)
        if not r.stopping:
            log.warning("%s (pid %d) exited by itself with %s", node, r.pid, how)
        if self._running.get(node) is r:
            del self._running[node]
            self._record_write()

    # -- the record of running nodes, and adopting them -----------------------------------
    def _digest(self, cfg: ProcessConfig) -> str:
        env = json.dumps({**self.env, **cfg.env}, sort_keys=True)
        return hashlib.sha256(env.encode()).hexdigest()[:16]

    def _record_write(self) -> None:
        """Write what runs now (pid, start time, argv, environment digest) atomically."""
        rec: dict[str, dict[str, object]] = {}
        for node, r in self._running.items():
            with contextlib.suppress(psutil.Error):
                rec[node] = {"pid": r.pid, "started": psutil.Process(r.pid).create_time(),
                             "argv": list(self.configs[node].argv),
                             "env": self._digest(self.configs[node])}
        self.logs.write_record(RECORD, json.dumps(rec, indent=1))

    async def adopt(self) -> dict[str, str]:
        """Take over the nodes an earlier daemon left running (see the module docstring);
        returns what was done with each recorded node (``adopted`` or why it was stopped)."""
        try:
            rec = json.loads((self.log_dir / RECORD).read_text())
        except (OSError, ValueError):
            return {}
        done: dict[str, str] = {}
        for node, info in rec.items() if isinstance(rec, dict) else ():
            try:
                pid = int(info["pid"])
                p = psutil.Process(pid)
                same = (abs(p.create_time() - float(info["started"])) < 0.01
                        and p.status() != psutil.STATUS_ZOMBIE)
            except (psutil.Error, KeyError, TypeError, ValueError):
                continue  # gone: nothing to do
            if not same:
                continue  # the pid was reused by something else: not ours
            cfg = self.configs.get(node)
            if (cfg is None or cfg.unit is not None or list(cfg.argv) != info.get("argv")
                    or self._digest(cfg) != info.get("env") or node in self._running):
                self._signal(pid, signal.SIGTERM)
                done[node] = "stopped: it ran another command or environment"
                continue
            logf = self.logs.open(node, f"--- {time.strftime('%Y-%m-%d %H:%M:%S')} adopted "
                                  f"pid {pid} (left running by an earlier daemon)\n")
            self._watch(node, _Running(pid, logf))
            done[node] = "adopted"
            if self.on_start is not None:
                self.on_start(node, pid)
        self._record_write()
        return done

    @staticmethod
    def _signal(pid: int, sig: signal.Signals) -> None:
        with contextlib.suppress(ProcessLookupError, PermissionError):
            os.killpg(pid, sig)  # the node's own session: the leader and its children

    # -- systemd ---------------------------------------------------------------------------
    def systemctl_argv(self, *args: str) -> list[str]:
        """The command line for ``systemctl ARGS`` (``--user`` when configured)."""
        return [self.systemctl, *(["--user"] if self.user else []), *args]

    async def _run(self, argv: list[str], timeout: float = 30.0) -> tuple[int, str]:
        try:
            proc = await asyncio.create_subprocess_exec(
                *argv, stdin=asyncio.subprocess.DEVNULL, stdout=asyncio.subprocess.PIPE,
                stderr=asyncio.subprocess.STDOUT)
        except OSError as exc:
            raise ProcessError(f"cannot run {argv[0]}: {exc.strerror or exc}") from exc
        try:
            out, _ = await asyncio.wait_for(proc.communicate(), timeout)
        except TimeoutError:
            proc.kill()
            await proc.wait()
            raise ProcessError(f"{' '.join(argv)} did not finish within {timeout:g} s") from None
        return proc.returncode or 0, out.decode(errors="replace").strip()

    async def _systemctl(self, verb: str, unit: str) -> None:
        argv = self.systemctl_argv(verb, unit)
        code, out = await self._run(argv)
        if code != 0:
            raise ProcessError(f"{' '.join(argv)} failed with status {code}: {out[:300]}")

    async def _main_pid(self, unit: str) -> int | None:
        code, out = await self._run(self.systemctl_argv("show", "-p", "MainPID", "--value", unit))
        if code != 0 or not out.isdigit() or int(out) == 0:
            return None
        return int(out)
