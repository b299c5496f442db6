"""Actuation through the board client: switch, power-cycle, clear, each read back and checked.

``BoardActuator`` is the board client's actuator: it holds the client's link
(``host.board.link``) and channel names (``host.board.channels``) and uses only their public
methods. Every command names a channel by
number or name, goes out signed with the key (on transports that authenticate) and comes back
as the board's read-back: the switch's physical state and the channel's state. A board that
acknowledges a command but reads back something else raises ``ReadbackMismatch`` (the switch
may be faulty), so a caller never believes a switch moved when it did not.
"""

from __future__ import annotations

import logging

from host.board.channels import ChannelNames
from host.board.link import BoardLink
from host.board.types import SwitchResult
from host.transports.base import AUTH
from host.transports.errors import BadRequest, KeyMissing, ReadbackMismatch
from protocol.constants import BOARD_CHANNEL, ST_INRUSH, ST_ON, STATE_NAMES
from protocol.messages import Ack, Clear, Message, PowerCycle, Switch, Switched

log = logging.getLogger(__name__)


def need_key(link: BoardLink, what: str) -> None:
    """``KeyMissing`` before anything is sent when the wire authenticates and there is no key
    (the codec cannot sign without one: a person gets one line saying where the key goes)."""
    if link.key is None and AUTH in link.transport.CAPS:
        raise KeyMissing(f"{link.url}: {what} needs the board's key, and none was given",
                         "set DXBOARD_KEY (hex) or pass --key-file FILE")


def readback_problem(reply: Switched, on: bool) -> str:
    """What in a SWITCHED disagrees with switching ``on`` (or off); "" when nothing does.
    Each part is named as it is: the command, the switch's read-back, the channel's state."""
    name = STATE_NAMES[reply.state] if reply.state < len(STATE_NAMES) else "unknown"
    want = "on" if on else "off"
    if reply.commanded != on:
        return f"the board reports it commanded {'on' if reply.commanded else 'off'}"
    if reply.physical != on:
        return f"its switch reads back {'on' if reply.physical else 'off'} (state {name})"
    if on and reply.state not in (ST_INRUSH, ST_ON):
        return f"its switch reads back {want} while the board reports the channel state {name}"
    return ""


class BoardActuator:
    """Switch, power-cycle and clear channels of the board behind ``link``."""

    def __init__(self, link: BoardLink, channels: ChannelNames) -> None:
        self.link = link
        self.channels = channels

    async def _switched(self, msg: Message, ch: int) -> Switched:
        reply: Switched = await self.link.expect(msg, Switched)
        if reply.channel != ch:
            raise ReadbackMismatch(f"{self.link.url}: asked about channel {ch}, "
                                   f"the board answered for {reply.channel}",
                                   "the firmware may not match this host")
        return reply

    async def _result(self, reply: Switched) -> SwitchResult:
        names = await self.channels.names()
        name = names[reply.channel] if reply.channel < len(names) else ""
        return SwitchResult(reply.channel, name, reply.commanded, reply.physical, reply.state)

    async def switch(self, ch: int | str, on: bool, force: bool = False) -> SwitchResult:
        """Switch a channel; the read-back must show the switch where it was asked to be."""
        need_key(self.link, "switching a channel")
        n = await self.channels.number(ch)
        reply = await self._switched(Switch(n, on, force), n)
        problem = readback_problem(reply, on)
        if problem:
            raise ReadbackMismatch(f"{self.link.url}: channel {n} was switched "
                                   f"{'on' if on else 'off'}, but {problem}",
                                   "the switch may be faulty: see `dxboard board URL status`")
        return await self._result(reply)

    async def power_cycle(self, ch: int | str, off_s: float = 1.0,
                          force: bool = False) -> SwitchResult:
        """Switch off, wait ``off_s``, switch on (the board times it where it can)."""
        need_key(self.link, "a power cycle")
        n = await self.channels.number(ch)
        off_ms = round(off_s * 1000)
        if not 0 <= off_ms <= 60000:
            raise BadRequest(f"off time {off_s} s is out of range", "use 0..60 s")
        reply = await self._switched(PowerCycle(n, off_ms, force), n)
        if reply.physical and off_ms:
            raise ReadbackMismatch(f"{self.link.url}: channel {n} should be off for {off_s:g} s "
                                   "but reads back on", "the switch may be stuck on")
        return await self._result(reply)

    async def clear(self, ch: int | str) -> SwitchResult | None:
        """Clear a channel's latch and sticky faults (``"all"``: every channel)."""
        need_key(self.link, "clearing a channel")
        if str(ch) == "all":
            await self.link.expect(Clear(BOARD_CHANNEL), Ack)
            return None
        n = await self.channels.number(ch)
        return await self._result(await self._switched(Clear(n), n))
