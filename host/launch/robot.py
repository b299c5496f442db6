"""Start a robot: its emulated board and devices when asked for, and the daemon, in one place.

``Launch(options)`` is the one way ``dxboard run``, the experiments and the tests start a robot.
As an async context manager it

1. loads and checks the robot directory (``load_robot``: model, observers, processes, repair
   domain), checks that the addresses it will listen on are free and opens the journal (one
   writer per journal: a second run on the same file is refused) — so that a mistake is one
   line before anything has started or been printed;
2. with ``board_url=None``, starts the robot's emulated board (``dxboard emulate``, with its
   devices when the robot has a ``robot.yaml``) as a child process and asks it, over its
   control endpoint, what the daemon needs: the devices' boot times (the repairs' settle times)
   and the device URLs its driver nodes connect to;
3. starts the ``Daemon`` on that board;

and on exit stops the daemon (and the nodes it started), then the emulator. ``lines()`` are the
``name: url`` lines a person needs (board, control, devices, web, journal).
"""

from __future__ import annotations

import dataclasses
import json
import logging
import socket
from dataclasses import dataclass
from pathlib import Path
from types import TracebackType

from host.daemon.core import Daemon, DaemonOptions, load_robot
from host.daemon.stream import Reader
from host.errors import UserError
from host.journal import Journal
from host.launch.control import arequest
from host.launch.emulated import EmulatedBoard

log = logging.getLogger(__name__)


@dataclass
class Launch:
    """What to start; ``board_url=None`` starts the robot's emulated board."""

    system_dir: Path
    board_url: str | None = None
    key: bytes | None = None
    control: str = "127.0.0.1:0"  # the emulated board's fault-injection endpoint
    daemon: DaemonOptions | None = None  # the rest of the daemon's options (board filled in)
    emulate_args: tuple[str, ...] = ()
    readers: tuple[Reader, ...] = ()  # readers of the daemon's event stream, from its start


def _check_free(host: str, port: int, what: str) -> None:
    if port == 0:
        return
    with socket.socket() as s:
        s.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)  # as the servers bind
        try:
            s.bind((host, port))
        except OSError as exc:
            raise UserError(f"{what}: cannot listen on {host}:{port}: {exc.strerror}",
                            "stop what uses it, or choose another address") from None


def _zenoh_port(endpoint: str) -> tuple[str, int] | None:
    proto, _, rest = endpoint.partition("/")
    host, sep, port = rest.rpartition(":")
    if proto != "tcp" or not sep or not port.isdigit():
        return None
    return host.strip("[]"), int(port)


class LaunchedRobot:
    def __init__(self, launch: Launch) -> None:
        self.launch = launch
        self.emulated: EmulatedBoard | None = None
        self._daemon: Daemon | None = None
        self._closing_daemon: Daemon | None = None
        self._closing = "nothing yet"

    @property
    def daemon(self) -> Daemon:
        if self._daemon is None:
            raise RuntimeError("the robot is not running")
        return self._daemon

    async def __aenter__(self) -> LaunchedRobot:
        la = self.launch
        opts = la.daemon or DaemonOptions(system_dir=la.system_dir, board_url="")
        files = load_robot(la.system_dir, opts.zenoh_listen, opts.middleware)
        if opts.web is not None:
            _check_free(*opts.web, "--web")
        for endpoint in files.observers.source.listen:
            zp = _zenoh_port(endpoint)
            if zp is not None:
                _check_free(*zp, "the topic source (--zenoh)")
        if la.board_url is None:
            host, _, port = la.control.rpartition(":")
            if port.isdigit():
                _check_free(host, int(port), "--control")
        journal = Journal(opts.journal) if opts.journal is not None else None  # one writer
        try:
            board_url, key, env, boot, fed = await self._board(opts)
            opts = dataclasses.replace(opts, board_url=board_url, key=key,
                                       node_env={**opts.node_env, **env},
                                       device_boot_s={**boot, **opts.device_boot_s},
                                       device_pids={**fed, **opts.device_pids})
            self._daemon = Daemon(opts, files=files)
            if journal is not None:
                self._daemon.attach_journal(journal)
                journal = None
            for reader in la.readers:
                self._daemon.subscribe(reader)
            await self._daemon.start()
        except BaseException:
            if journal is not None:
                journal.close()
            await self.close()
            raise
        return self

    async def _board(self, opts: DaemonOptions) -> tuple[
            str, bytes | None, dict[str, str], dict[str, float], dict[str, int]]:
        """The board's URL and key, the nodes' environment, the devices' boot times and the
        pid of the process that emulates each device (its starvation is the topics')."""
        la = self.launch
        if la.board_url is not None:
            return la.board_url, la.key, {}, {}, {}
        extra = la.emulate_args
        if (la.system_dir / "robot.yaml").is_file() and "--robot" not in extra:
            extra = ("--robot", *extra)
        emu = self.emulated = await EmulatedBoard.start(la.system_dir, la.control, extra,
                                                        key=la.key)
        hello = await arequest(emu.control_url, {"op": "hello"})
        boot = {str(k): float(v) / 1000.0 for k, v in dict(hello.get("boot_ms", {})).items()}
        env = {"DXBOARD_DEVICES": json.dumps(emu.devices)} if emu.devices else {}
        return emu.board_url, emu.key, env, boot, {d: emu.proc.pid for d in emu.devices}

    async def __aexit__(self, exc_type: type[BaseException] | None,
                        exc: BaseException | None, tb: TracebackType | None) -> None:
        await self.close()

    @property
    def closing(self) -> str:
        """What ``close()`` is closing now (``host.launch.stopping`` reports it)."""
        d = self._closing_daemon
        return self._closing if d is None else f"the daemon to close {d.closing}"

    async def close(self) -> None:
        """Stop the daemon (and its nodes), then the emulator; idempotent."""
        try:
            if self._daemon is not None:
                daemon, self._daemon = self._daemon, None
                self._closing_daemon = daemon
                await daemon.close()
        finally:
            self._closing_daemon = None
            if self.emulated is not None:
                emu, self.emulated = self.emulated, None
                self._closing = "the emulated board"
                await emu.stop()
            self._closing = "the process to exit"

    def lines(self) -> list[str]:
        """The ``name: url`` lines a person needs to reach the robot."""
        d = self.daemon
        out = [f"board: {d.opts.board_url}"]
        if self.emulated is not None:
            out.append(f"control: {self.emulated.control_url}")
            out += [f"device: {n} {u}" for n, u in sorted(self.emulated.devices.items())]
        if d.web_port is not None and d.opts.web is not None:
            out.append(f"web: http://{d.opts.web[0]}:{d.web_port}/")
        if d.operator is not None:
            out.append(f"operator: {d.operator.path}")
        if d.opts.journal is not None:
            out.append(f"journal: {d.opts.journal}")
        return out
