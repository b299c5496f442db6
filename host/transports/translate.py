"""The half shared by transports whose wire is not the native protocol (modbus, can, tug).

Theory of operation. The board client sends protocol messages and waits for replies with its
own timeout, so ``send`` must return at once: a ``TranslatingTransport`` looks up the handler
for the message's type (``handlers()``: type -> coroutine function), runs it as a task, and
puts its result into an inbox with the request's ``req_id``; ``receive`` reads the inbox.
A handler raises ``Refused(code, text)`` for what the board refused (it becomes an ERROR reply,
as on the native protocol) and ``OSError`` when the link broke (the inbox then ends with
``LinkLost``). Pushes (measurements the transport polls or the board broadcasts) go in with
``push``. A message without a handler is ``NotSupported`` before anything is sent. A power
cycle the wire cannot express is done here as off, wait, on (``emulated_cycle``).
A wire that carries no events but each channel's live flags (Modbus, CAN) gets the ``low``
flag's range EVENTs from ``RangeEvents``: made from the flag's changes between two polls and
pushed before the reading that shows them, as the native board pushes them (PROTOCOL.md
section 10), so that a host knows a 0 it cannot measure from one it can.
"""

from __future__ import annotations

import asyncio
import contextlib
import logging
import time
from collections.abc import Awaitable, Callable, Sequence
from typing import Any

from host.transports.base import Transport
from host.transports.errors import LinkLost, NotSupported
from host.transports.url import BoardUrl
from protocol.constants import ERROR_TEXT, EV_RANGE, F_LOW
from protocol.framing import BadFrame
from protocol.messages import Error, Event, Message, PowerCycle, Switch, Switched

log = logging.getLogger(__name__)

Handler = Callable[[Any], Awaitable[Message | None]]


class WireRefused(Exception):
    """The board (or the wire's server) refused a request: ``code`` is an E_* code."""

    def __init__(self, code: int, text: str = "", modbus: int = 0) -> None:
        super().__init__(text or ERROR_TEXT.get(code, "refused"))
        self.code = code
        self.text = text or ERROR_TEXT.get(code, "refused")
        self.modbus = modbus  # the wire's own exception code, where it has one


class TranslatingTransport(Transport):
    def __init__(self, url: BoardUrl, key: bytes | None = None) -> None:
        super().__init__(url, key)
        self._inbox: asyncio.Queue[Message | BadFrame | None] = asyncio.Queue()
        self._tasks: set[asyncio.Task[Any]] = set()
        self._lost = ""
        self._cycles: set[asyncio.Task[Any]] = set()
        self.opened_at = time.monotonic()

    def handlers(self) -> dict[type[Message], Handler]:
        raise NotImplementedError

    def uptime_ms(self) -> int:
        """Milliseconds since the link opened (for wires that report no uptime)."""
        return int((time.monotonic() - self.opened_at) * 1000) & 0xFFFFFFFF

    def spawn(self, coro: Awaitable[Any]) -> asyncio.Task[Any]:
        task = asyncio.ensure_future(coro)
        self._tasks.add(task)
        task.add_done_callback(self._tasks.discard)
        return task

    def push(self, msg: Message | BadFrame) -> None:
        self._inbox.put_nowait(msg)

    def lose(self, reason: str) -> None:
        if not self._lost:
            self._lost = reason or "link lost"
            self._inbox.put_nowait(None)

    def supports(self, msg: Message) -> bool:
        """False for a message of a handled type that this wire still cannot carry."""
        return True

    async def _send(self, msg: Message) -> None:
        handler = self.handlers().get(type(msg))
        if handler is None or not self.supports(msg):
            raise NotSupported(f"{self.url.text}: {type(msg).__name__} is not possible over "
                               f"{self.SCHEME}", "use the board's native transport (tcp://)")
        self.spawn(self._run(handler, msg))

    async def _run(self, handler: Handler, msg: Message) -> None:
        try:
            reply = await handler(msg)
        except WireRefused as exc:
            self.push(Error(exc.code, msg.TYPE, exc.text, req_id=msg.req_id))
            return
        except (OSError, LinkLost) as exc:
            self.lose(str(exc))
            return
        if reply is not None:
            reply.req_id = msg.req_id
            self.push(reply)

    async def _receive(self) -> Message | BadFrame:
        item = await self._inbox.get()
        if item is None:
            self._inbox.put_nowait(None)  # every later receive fails the same way
            raise LinkLost(f"{self.url.text}: {self._lost}", "the board may have rebooted")
        return item

    async def _close(self) -> None:
        if self._cycles:  # let power cycles the host times finish (switch back on)
            await asyncio.wait(list(self._cycles), timeout=65)
        for task in list(self._tasks):
            task.cancel()
            with contextlib.suppress(asyncio.CancelledError, Exception):
                await task
        await self._disconnect()

    async def _disconnect(self) -> None:
        raise NotImplementedError

    async def emulated_cycle(self, switch: Callable[[int, bool], Awaitable[None]], ch: int,
                             off_ms: int) -> None:
        """A power cycle done by the host: off now, on after ``off_ms`` (in the background)."""
        await switch(ch, False)

        async def later() -> None:
            await asyncio.sleep(off_ms / 1000)
            try:
                await switch(ch, True)
            except (OSError, WireRefused) as exc:
                log.warning("%s: power cycle of channel %d: switching on failed: %s",
                            self.url.text, ch, exc)

        task = self.spawn(later())
        self._cycles.add(task)
        task.add_done_callback(self._cycles.discard)

    # --- wires with a plain on/off command (modbus, tug): the host times power cycles ---

    async def _switch(self, ch: int, on: bool) -> None:
        """Send the wire's on/off command for channel ``ch``."""
        raise NotImplementedError

    async def _read_back(self, ch: int, want: bool) -> Switched:
        """The channel read back after switching it (waiting briefly for ``want``)."""
        raise NotImplementedError

    async def _on_switch(self, msg: Switch) -> Message:
        await self._switch(msg.channel, msg.on)
        return await self._read_back(msg.channel, msg.on)

    async def _on_cycle(self, msg: PowerCycle) -> Message:
        await self.emulated_cycle(self._switch, msg.channel, msg.off_ms)
        back = await self._read_back(msg.channel, False)
        return Switched(back.channel, True, back.physical, back.state)


class RangeEvents:
    """The range EVENTs of the ``low`` flag for a wire without events (see the module
    docstring): ``changes`` compares each channel's live flags with the last poll's."""

    def __init__(self) -> None:
        self.low = 0  # channel k's bit: ``low`` was live at the last poll
        self.seq = 0

    def changes(self, uptime_ms: int, live: Sequence[int], states: Sequence[int],
                currents: Sequence[int]) -> list[Event]:
        out = []
        for k, flags in enumerate(live):
            low = bool(flags & F_LOW)
            if low != bool(self.low >> k & 1):
                self.low ^= 1 << k
                self.seq += 1
                st = states[k] if k < len(states) else 0
                ma = currents[k] if k < len(currents) and not low else 0
                out.append(Event(self.seq, uptime_ms, EV_RANGE, k, st, st,
                                 F_LOW if low else 0, ma))
        return out
