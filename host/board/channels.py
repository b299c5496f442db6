"""The board's channels by number or by name, the names read once per board.

``ChannelNames`` answers "which channel is ``kinect``?" for the board client and its actuator
and configurator: names come from the board's configuration (one GETCONFIG a channel, where the
transport can read names: ``NAMES`` in its ``CAPS``; ``ch<N>`` otherwise), read on first use
and kept for as long as the link talks to the same board (a new ``board_id`` reads them
again); ``forget()`` after a channel was renamed.
"""

from __future__ import annotations

from host.board.link import BoardLink
from host.transports.base import NAMES
from host.transports.errors import BadChannel
from protocol.messages import ChannelConfig, GetConfig


class ChannelNames:
    """See the module docstring."""

    def __init__(self, link: BoardLink) -> None:
        self.link = link
        self._names: list[str] | None = None
        self._board_id: str | None = None  # whose names they are

    def forget(self) -> None:
        """Read the names again on next use (a channel was renamed)."""
        self._names = None

    async def names(self) -> list[str]:
        """Channel names from the board's configuration ("ch<N>" where it cannot say)."""
        info = self.link.info
        board_id = info.board_id if info else None
        if self._names is None or board_id != self._board_id:
            n = info.channels if info else 0
            names = [f"ch{i}" for i in range(n)]
            if NAMES in self.link.transport.CAPS:
                for i in range(n):
                    cfg: ChannelConfig = await self.link.expect(GetConfig(i), ChannelConfig)
                    names[i] = cfg.name or names[i]
            self._names, self._board_id = names, board_id
        return list(self._names)

    async def number(self, ch: int | str) -> int:
        """The channel number for a number or a name; ``BadChannel`` if there is none."""
        names = await self.names()
        text = str(ch).strip()
        if text.isdigit() and int(text) < len(names):
            return int(text)
        if text in names:
            return names.index(text)
        raise BadChannel(f"{self.link.url}: no channel {text!r}",
                         f"use 0..{len(names) - 1} or one of: {', '.join(names)}")
