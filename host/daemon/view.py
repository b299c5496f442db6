"""The board as the daemon shows it: channel names, states and currents, from the board stream.

``BoardView`` folds the board client's values into what the web page and the metrics need:
``reset(state)`` takes a whole ``BoardState`` (after connecting, reconnecting or a reboot),
``apply(item)`` one stream item (a reading's currents and on-mask; an event's new state), and
``channels()`` gives the page's ``ChannelStatus`` tuple with a short history of currents for
the sparklines. It holds no I/O and reads no clock: a pure fold over the stream, kept apart so
the daemon only wires.
"""

from __future__ import annotations

from collections import deque
from dataclasses import dataclass, field

from host.board.types import BoardEvent, BoardState, Reading, StreamItem
from host.web.status import ChannelStatus
from protocol.constants import EV_STATE, EV_TRIP, STATE_NAMES

HISTORY = 120  # sparkline points per channel


@dataclass
class _Channel:
    name: str
    state: int = 0
    on: bool = False
    current_ma: float = 0.0
    history: deque[float] = field(default_factory=lambda: deque(maxlen=HISTORY))


class BoardView:
    def __init__(self) -> None:
        self._channels: list[_Channel] = []
        self.latest: Reading | None = None

    def reset(self, state: BoardState) -> None:
        """Take the whole board (names, states, currents) from a fresh ``BoardState``."""
        old = {c.name: c.history for c in self._channels}
        self._channels = [
            _Channel(
                ch.name,
                ch.state,
                ch.physical,
                float(ch.current_ma),
                old.get(ch.name, deque(maxlen=HISTORY)),
            )
            for ch in state.channels
        ]

    def apply(self, item: StreamItem) -> None:
        """Fold one stream item in (link notices change nothing here)."""
        if isinstance(item, Reading):
            self.latest = item
            for i, c in enumerate(self._channels):
                if i < len(item.currents_ma):
                    c.current_ma = float(item.currents_ma[i])
                c.on = bool(item.on_mask >> i & 1)
        elif (
            isinstance(item, BoardEvent)
            and item.kind in (EV_STATE, EV_TRIP)
            and 0 <= item.channel < len(self._channels)
        ):
            self._channels[item.channel].state = item.new_state

    def sample(self) -> None:
        """Append every channel's current to its sparkline (the daemon calls it at a steady
        rate, so the sparkline's time axis is even whatever the board's rate)."""
        for c in self._channels:
            c.history.append(c.current_ma)

    def channels(self) -> tuple[ChannelStatus, ...]:
        return tuple(
            ChannelStatus(
                id=i,
                name=c.name,
                on=c.on,
                state=STATE_NAMES[c.state] if 0 <= c.state < len(STATE_NAMES) else str(c.state),
                current_ma=c.current_ma,
                history_ma=tuple(c.history),
            )
            for i, c in enumerate(self._channels)
        )

    def names(self) -> list[str]:
        return [c.name for c in self._channels]
