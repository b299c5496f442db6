"""Starting and stopping nodes: processes the host supervises itself, and systemd units.

``ProcessSupervisor(configs, log_dir)`` is the actuator behind ``start_node``/``stop_node``
(configured by ``processes:`` in ``system.yaml``, see ``host.repair.processes``):

- a ``command`` node runs as an asyncio subprocess in its own session (process group), its
  stdout and stderr appended to ``log_dir/<node>.log`` with a header line per start and a
  footer line with the exit status; ``stop`` sends SIGTERM to the whole group, then SIGKILL
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
"""

from __future__ import annotations

import asyncio
import contextlib
import logging
import os
import signal
import time
from collections.abc import Callable, Mapping
from pathlib import Path
from typing import IO

from host.errors import RemoteError
from host.repair.processes import ProcessConfig

log = logging.getLogger(__name__)

OnStart = Callable[[str, int], None]


class ProcessError(RemoteError):
    """A node could not be started or stopped (no configuration, exec failed, systemctl)."""


class _Running:
    def __init__(self, proc: asyncio.subprocess.Process, logf: IO[bytes]) -> None:
        self.proc = proc
        self.logf = logf
        self.stopping = False
        self.reaper: asyncio.Task[None] | None = None


class ProcessSupervisor:
    def __init__(self, configs: Mapping[str, ProcessConfig], log_dir: str | Path, *,
                 on_start: OnStart | None = None, user: bool = False,
                 systemctl: str = "systemctl", env: Mapping[str, str] | None = None) -> None:
        self.configs = dict(configs)
        self.env = dict(env or {})  # for every process, under each one's own env
        self.log_dir = Path(log_dir)
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
        if r is not None and r.proc.returncode is None:
            return r.proc.pid
        return self._units.get(node)

    def log_file(self, node: str) -> Path:
        return self.log_dir / f"{node}.log"

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
        if r is None or r.proc.returncode is not None:
            return None
        r.stopping = True
        self._signal(r.proc.pid, signal.SIGTERM)
        try:
            await asyncio.wait_for(asyncio.shield(r.proc.wait()), cfg.stop_timeout_s)
        except TimeoutError:
            log.warning("%s did not stop within %g s of SIGTERM: SIGKILL", node,
                        cfg.stop_timeout_s)
            self._signal(r.proc.pid, signal.SIGKILL)
            await r.proc.wait()
        self._signal(r.proc.pid, signal.SIGKILL)  # children that outlived the leader
        if r.reaper is not None:
            await r.reaper
        return r.proc.returncode

    async def close(self) -> None:
        """Stop every process this supervisor started (units are left to systemd)."""
        for node in list(self._running):
            await self.stop(node)

    # -- processes the host runs -----------------------------------------------------------
    async def _spawn(self, cfg: ProcessConfig) -> int:
        node = cfg.node
        r = self._running.get(node)
        if r is not None and r.proc.returncode is None:
            return r.proc.pid
        self.log_dir.mkdir(parents=True, exist_ok=True)
        logf = self.log_file(node).open("ab")
        stamp = time.strftime("%Y-%m-%d %H:%M:%S")
        logf.write(f"--- {stamp} start: {' '.join(cfg.argv)}\n".encode())
        logf.flush()
        try:
            proc = await asyncio.create_subprocess_exec(
                *cfg.argv, stdin=asyncio.subprocess.DEVNULL, stdout=logf,
                stderr=asyncio.subprocess.STDOUT, cwd=cfg.cwd,
                env={**os.environ, **self.env, **cfg.env}, start_new_session=True)
        except OSError as exc:
            logf.write(f"--- cannot start: {exc}\n".encode())
            logf.close()
            raise ProcessError(f"cannot start {node}: {exc.strerror or exc} ({cfg.argv[0]})"
                               ) from exc
        r = self._running[node] = _Running(proc, logf)
        r.reaper = asyncio.get_running_loop().create_task(self._reap(node, r),
                                                           name=f"reap:{node}")
        log.info("started %s as pid %d", node, proc.pid)
        return proc.pid

    async def _reap(self, node: str, r: _Running) -> None:
        code = await r.proc.wait()
        self.exits[node] = code
        how = f"signal {-code}" if code < 0 else f"status {code}"
        r.logf.write(f"--- exited with {how}{' (stopped)' if r.stopping else ''}\n".encode())
        r.logf.close()
        if not r.stopping:
            log.warning("%s (pid %d) exited by itself with %s", node, r.proc.pid, how)
        if self._running.get(node) is r:
            del self._running[node]

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
