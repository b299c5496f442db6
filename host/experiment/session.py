"""The virtual robot and the daemon in this process, for experiments and the fault campaign.

``RobotSession(system_dir, journal)`` is an async context manager: on entry it starts the
robot's emulated board and devices as a child process and a ``Daemon`` on a free zenoh port,
without a web page, journaling to ``journal`` — through ``host.launch``, exactly as ``dxboard
run --emulate`` does; on exit it stops the daemon (and the nodes it started), then the
emulator. The
daemon runs in this process so that an experiment reads its state directly (is it healthy,
is a repair running) and its clock is the journal's; the board and the devices stay behind
their process boundary, as on a real robot.

``t0`` is the daemon's start on its monotonic clock; every time an experiment reports is
seconds since ``t0`` (or since a mark it takes). ``switch`` acts as an operator with the
board's key would (``dxboard board URL off CH``); ``inject`` and ``clear`` are ``dxboard
inject`` on the control endpoint.
"""

from __future__ import annotations

import asyncio
import contextlib
import time
from pathlib import Path
from types import TracebackType
from typing import Any

from host.board import BoardClient
from host.daemon.core import Daemon, DaemonOptions
from host.errors import UserError
from host.journal import Entry, JournalReader
from host.launch.control import arequest
from host.launch.emulated import EmulatedBoard
from host.launch.ports import free_port
from host.launch.robot import Launch, LaunchedRobot


def beside(journal: Path, label: str) -> Path:
    """FILE-label.sqlite beside the journal FILE (a second run of an experiment journals there)."""
    return journal.with_name(f"{journal.stem}-{label}{journal.suffix or '.sqlite'}")


class RobotSession:
    def __init__(self, system_dir: Path, journal: Path, *, max_parallel: int | None = None,
                 debounce_s: float = 0.5, emulate_args: tuple[str, ...] = (),
                 web: tuple[str, int] | None = None) -> None:
        self.system_dir = system_dir
        self.journal_path = journal
        opts = DaemonOptions(
            system_dir=system_dir, board_url="", web=web, journal=journal,
            zenoh_listen=[f"tcp/127.0.0.1:{free_port()}"], repair_debounce_s=debounce_s,
            max_parallel_steps=max_parallel)
        self.robot = LaunchedRobot(Launch(system_dir, daemon=opts, emulate_args=emulate_args))
        self._runner: asyncio.Task[None] | None = None
        self.t0 = 0.0

    @property
    def daemon(self) -> Daemon:
        return self.robot.daemon

    @property
    def emulated(self) -> EmulatedBoard:
        if self.robot.emulated is None:
            raise RuntimeError("the session is not running")
        return self.robot.emulated

    async def __aenter__(self) -> RobotSession:
        await self.robot.__aenter__()
        self.t0 = self.daemon.clock()
        self._runner = asyncio.ensure_future(self.daemon.wait())
        return self

    async def __aexit__(self, exc_type: type[BaseException] | None,
                        exc: BaseException | None, tb: TracebackType | None) -> None:
        if self._runner is not None:
            self.daemon.stop()  # its wait() ends by itself, leaving no task behind
            await asyncio.wait([self._runner], timeout=5.0)
            self._runner.cancel()
            with contextlib.suppress(asyncio.CancelledError):
                await self._runner
        await self.robot.close()

    # --- state ------------------------------------------------------------------------------

    def now(self) -> float:
        """Seconds since the daemon started."""
        return self.daemon.clock() - self.t0

    def check(self) -> None:
        """Raise what made the daemon stop, if it did."""
        if self._runner is not None and self._runner.done():
            self._runner.result()
            raise UserError("the daemon stopped by itself")

    def repairing(self) -> bool:
        return self.daemon.repairs.active

    def healthy(self) -> bool:
        """The board is heard, nothing is diagnosed abnormal and no repair is running."""
        d = self.daemon
        return d.link_up and d.healthy() and not self.repairing()

    async def wait_healthy(self, timeout_s: float, hold_s: float = 1.0) -> bool:
        """Wait until healthy for ``hold_s`` without a break; False on timeout."""
        end = time.monotonic() + timeout_s
        since: float | None = None
        while time.monotonic() < end:
            self.check()
            if self.healthy():
                since = since if since is not None else time.monotonic()
                if time.monotonic() - since >= hold_s:
                    return True
            else:
                since = None
            await asyncio.sleep(0.1)
        return False

    async def wait_unhealthy(self, timeout_s: float) -> bool:
        """Wait until something is diagnosed abnormal (or a repair starts); False on timeout."""
        end = time.monotonic() + timeout_s
        while time.monotonic() < end:
            self.check()
            if not self.healthy():
                return True
            await asyncio.sleep(0.05)
        return False

    async def entries(self, after_id: int = 0) -> list[Entry]:
        """The journal so far (everything the daemon recorded, flushed first)."""
        if self.daemon.journal is not None:
            await self.daemon.journal.flush()
        with JournalReader(self.journal_path) as reader:
            return reader.query(after_id=after_id)

    async def last_id(self) -> int:
        got = await self.entries()
        return got[-1].id if got else 0

    # --- acting on the robot ------------------------------------------------------------------

    async def shut_down(self, device: str) -> None:
        """The device goes down (paper 000's device shut-down): its channel is switched off
        under the daemon, which must find and repair it — not a person's deliberate
        switch-off, which the daemon would hold (``switch``)."""
        ch = self.daemon.model.components[device].channel
        assert ch is not None, f"{device} is not on a board channel"
        self.daemon.repairs.executor.actuators.note_command(ch, False)
        await self.switch(device, False)

    async def switch(self, channel: str, on: bool) -> None:
        """Switch a channel as an operator with the key would."""
        async with BoardClient(self.emulated.board_url, self.emulated.key) as client:
            await client.switch(channel, on)

    async def inject(self, channel: str, fault: str, params: dict[str, Any] | None = None) -> None:
        await self.control({"op": "inject", "channel": channel, "fault": fault,
                             "params": params or {}})

    async def clear(self) -> None:
        await self.control({"op": "clear"})

    async def control(self, req: dict[str, Any]) -> None:
        await arequest(self.emulated.control_url, req)

    def forgive(self) -> None:
        """A person clears every quarantine and the attempt counts (between campaign faults)."""
        r = self.daemon.repairs
        for c in list(r.executor.quarantine.components):
            r.executor.clear_quarantine(c)
        for c in self.daemon.model.components:
            r.executor.limiter.reset(c)
