"""Actuators: a plan step's action name -> what is done on the robot, and nothing else.

``Actuators(model, board, supervisor)`` maps the repair domain's actions to the two kinds of
actuator the host has:

- board power: ``power_up(d)``, ``shutdown(d)`` and ``power_cycle(d)`` switch the board
  channel of switchable device ``d`` through the host's ``BoardClient``; the client checks the
  board's read-back (``ReadbackMismatch`` when the switch did not move). A channel the board
  latched or marked faulted is cleared first (it refuses to switch on otherwise); the
  executor's attempt limit bounds how often. Switch-ons (and the
  on-edge of a power cycle) are spaced at least ``spacing_s`` apart, whichever steps run in
  parallel, so inrush currents never add up (the board spaces its own power-up queue the same
  way, ``powerup_spacing_ms``);
- processes: ``start_node(n)`` and ``stop_node(n)`` through the ``ProcessSupervisor``;
- further actuators a middleware brings, registered with ``add(action, fn)`` (with ROS 2:
  ``reconfigure_node(n)``, ``host.ros.lifecycle``).

Protected components — the devices on the board's protected channels, the planner's
``channelN`` objects for protected channels without a device, and any component listed in
``protected`` — are never switched off here, whatever step is asked for: defence in depth, the
planner already drops such steps. A refused step raises ``Refused``; every other failure raises
``ActuationError`` (a ``RemoteError``) or lets the board client's ``TransportError`` through.
``ACTIONS`` is the name -> method registry; unknown actions are ``Refused`` (a domain that
declares an action the host cannot carry out).
"""

from __future__ import annotations

import asyncio
import logging
import time
from collections.abc import Awaitable, Callable, Iterable
from typing import TYPE_CHECKING

from host.errors import RemoteError, UserError
from host.repair.problem import protected_channel_object
from host.repair.supervisor import ProcessError
from protocol.constants import F_SHORT, ST_FAULTED, ST_INRUSH, ST_LATCHED, ST_TRIPPED

BOARD_RETRY_WAIT_S = 6.0  # longer than the board's longest default retry delay (5 s)

if TYPE_CHECKING:
    from host.board.client import BoardClient
    from host.diagnosis.model import SystemModel
    from host.planning.plan import Step
    from host.repair.supervisor import ProcessSupervisor

log = logging.getLogger(__name__)

DEFAULT_SPACING_S = 0.2
DEFAULT_OFF_S = 1.0
RECENT = 100  # switch commands and switch-ons remembered (the latest; a daemon runs for weeks)
SWITCH_OFF = frozenset({"shutdown", "power_cycle", "stop_node", "power_down"})


class ActuationError(RemoteError):
    """A step could not be carried out on the robot; the message says why, ``hint`` what to do."""


class Unsafe(ActuationError):
    """Acting would be unsafe by the board's own judgement (a channel it latched for a short
    circuit): the device goes to quarantine at once, for a person to look at."""

    def __init__(self, device: str, message: str, hint: str = "") -> None:
        super().__init__(message, hint)
        self.device = device


class Refused(UserError):
    """A step was refused before anything was done (a protected component, an action the host
    cannot carry out, a bad argument): the plan asked for it, nothing was touched."""


class Actuators:
    def __init__(self, model: SystemModel, board: BoardClient | None = None,
                 supervisor: ProcessSupervisor | None = None, *,
                 protected: Iterable[str] = (), spacing_s: float = DEFAULT_SPACING_S,
                 off_s: float = DEFAULT_OFF_S, clock: Callable[[], float] = time.monotonic
                 ) -> None:
        self.model = model
        self.board = board
        self.supervisor = supervisor
        self.spacing_s = spacing_s
        self.off_s = off_s
        self.clock = clock
        self.protected_channels = frozenset(model.protected)
        prot = {c.name for c in model.components.values()
                if c.channel is not None and c.channel in model.protected}
        prot |= {protected_channel_object(ch) for ch in model.protected}
        self.protected = frozenset(prot | set(protected))
        #: (clock time, channel) of the latest switch-ons sent (RECENT), for journals and tests
        self.switch_ons: list[tuple[float, int]] = []
        #: (clock time, channel, on) of the latest switch commands sent (RECENT), so that the
        #: daemon can tell its own commands from a person's
        self.commands: list[tuple[float, int, bool]] = []
        #: node -> clock time of the latest stop_node sent (a run it ended is no crash)
        self.stops: dict[str, float] = {}
        self._may_unlatch_short: set[str] = set()
        self._on_lock = asyncio.Lock()
        self._next_on = 0.0
        self._actions: dict[str, Callable[[str], Awaitable[str]]] = {
            "power_up": self.power_up, "shutdown": self.shutdown,
            "power_cycle": self.power_cycle, "start_node": self.start_node,
            "stop_node": self.stop_node,
        }

    def add(self, action: str, fn: Callable[[str], Awaitable[str]]) -> None:
        """Carry out ``action`` with ``fn(arg)`` (returns a one-line description)."""
        self._actions[action] = fn

    @property
    def actions(self) -> frozenset[str]:
        return frozenset(self._actions)

    def check(self, step: Step) -> None:
        """Raise ``Refused`` if ``step`` cannot be run at all (before any time is spent)."""
        if step.action not in self._actions:
            raise Refused(f"{step}: no actuator for action {step.action!r}",
                          f"the host carries out {', '.join(sorted(self._actions))}")
        if len(step.args) != 1:
            raise Refused(f"{step}: expected one argument")
        if step.action in SWITCH_OFF:
            self._never_off(step.action, step.args[0])

    def _never_off(self, action: str, name: str) -> None:
        if name in self.protected:
            raise Refused(f"{action}({name}) refused: {name} is protected and is never "
                          "switched off")

    async def run(self, step: Step) -> str:
        """Carry out ``step``; a one-line description of what was done."""
        self.check(step)
        return await self._actions[step.action](step.args[0])

    # -- board power -----------------------------------------------------------------------
    def _channel(self, device: str) -> tuple[int, BoardClient]:
        c = self.model.components.get(device)
        if c is None or c.channel is None:
            raise Refused(f"{device} is not a switchable device on a board channel")
        if self.board is None:
            raise ActuationError(f"no board to switch {device}")
        return c.channel, self.board

    async def _spaced(self, on_at_offset: float, send: Callable[[], Awaitable[str]]) -> str:
        """Send a command whose switch-on happens ``on_at_offset`` s after it is sent, no
        sooner than ``spacing_s`` after the previous switch-on."""
        async with self._on_lock:
            delay = self._next_on - on_at_offset - self.clock()
            if delay > 0:
                await asyncio.sleep(delay)
            out = await send()
            on_at = self.clock() + on_at_offset
            self._next_on = on_at + self.spacing_s
            return out

    def allow_unlatch(self, device: str) -> None:
        """A person looked at ``device``: its channel may be cleared once even if the board
        latched it for a short circuit."""
        self._may_unlatch_short.add(device)

    def _sent(self, ch: int, on: bool) -> None:
        self.commands.append((self.clock(), ch, on))
        del self.commands[:-RECENT]

    def _switched_on(self, t: float, ch: int) -> None:
        self.switch_ons.append((t, ch))
        del self.switch_ons[:-RECENT]

    def note_command(self, ch: int, on: bool) -> None:
        """A switch command sent on this host's behalf by something else in its process (an
        experiment standing in for a device that fails): not a person's deliberate switch."""
        self._sent(ch, on)

    def sent_recently(self, ch: int, on: bool, within_s: float) -> bool:
        """True when this host sent ``ch`` that command within the last ``within_s``."""
        now = self.clock()
        return any(c == ch and o == on and now - t <= within_s for t, c, o in self.commands)

    async def power_up(self, device: str) -> str:
        ch, board = self._channel(device)

        async def send() -> str:
            cleared = await self._unlatch(board, ch, device)
            self._sent(ch, True)
            res = await board.switch(ch, True)
            self._switched_on(self.clock(), ch)
            return f"channel {ch} {cleared}on ({res.state_name})"

        return await self._spaced(0.0, send)

    async def _unlatch(self, board: BoardClient, ch: int, device: str) -> str:
        """Make the channel switchable. The board's own protection comes first: a channel it
        tripped has a retry pending, so wait for that retry to end (up to
        ``BOARD_RETRY_WAIT_S``, and no longer than the board takes to retry or latch) rather
        than fight it: the retry's inrush is part of it (it may trip again and latch), so the
        wait ends on a settled state, not on the retry's first reading. A channel it
        latched (or marked faulted) refuses to switch on until cleared: clear it — unless the
        board latched it for a short circuit: energising a short again is the board's call
        (its retries), not ours; that raises ``Unsafe`` until a person allows one try."""
        end = self.clock() + BOARD_RETRY_WAIT_S
        chan = (await board.state()).channels[ch]
        while chan.state in (ST_TRIPPED, ST_INRUSH) and self.clock() < end:
            await asyncio.sleep(0.1)
            chan = (await board.state()).channels[ch]
        if chan.state in (ST_LATCHED, ST_FAULTED):
            if chan.sticky_faults & F_SHORT and device not in self._may_unlatch_short:
                raise Unsafe(device, f"channel {ch} ({device}) was latched by the board for a "
                             "short circuit: not energised again",
                             f"check {device} and its wiring, then clear its quarantine")
            self._may_unlatch_short.discard(device)
            await board.clear(ch)
            return "cleared and "
        return ""

    async def shutdown(self, device: str) -> str:
        self._never_off("shutdown", device)
        ch, board = self._channel(device)
        if ch in self.protected_channels:
            raise Refused(f"shutdown({device}) refused: channel {ch} is protected")
        self._sent(ch, False)
        res = await board.switch(ch, False)  # never force: the board refuses too
        return f"channel {ch} off ({res.state_name})"

    async def power_cycle(self, device: str) -> str:
        self._never_off("power_cycle", device)
        ch, board = self._channel(device)
        if ch in self.protected_channels:
            raise Refused(f"power_cycle({device}) refused: channel {ch} is protected")

        async def send() -> str:
            await self._unlatch(board, ch, device)
            self._sent(ch, False)
            self._sent(ch, True)
            res = await board.power_cycle(ch, self.off_s)
            self._switched_on(self.clock() + self.off_s, ch)
            # the read-back is the middle of the cycle: the board switches on by its own timer
            return (f"channel {ch} off for {self.off_s:g} s (read back {res.state_name}), "
                    "on again by the board's timer")

        return await self._spaced(self.off_s, send)

    # -- processes -------------------------------------------------------------------------
    def _node(self, node: str) -> ProcessSupervisor:
        c = self.model.components.get(node)
        if c is None or not c.is_node:
            raise Refused(f"{node} is not a node of the model")
        if self.supervisor is None:
            raise ActuationError(f"no process supervisor to start or stop {node}")
        return self.supervisor

    async def start_node(self, node: str) -> str:
        sup = self._node(node)
        try:
            pid = await sup.start(node)
        except ProcessError as exc:
            raise ActuationError(str(exc)) from exc
        return f"{node} started" + (f" as pid {pid}" if pid is not None else "")

    async def stop_node(self, node: str) -> str:
        self._never_off("stop_node", node)
        sup = self._node(node)
        self.stops[node] = self.clock()
        try:
            code = await sup.stop(node)
        except ProcessError as exc:
            raise ActuationError(str(exc)) from exc
        return f"{node} stopped" + (f" (exit {code})" if code is not None else "")
