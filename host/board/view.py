"""The board as a person sees it: channel names, states and currents, folded from its stream.

``BoardView`` folds the board client's values into the channels' current picture: ``reset(state)``
takes a whole ``BoardState`` (after connecting, reconnecting or a reboot), ``apply(item)`` one
stream item (a reading's currents, on-mask and input voltage; an event's new state),
``sample()`` the picture now as a ``ChannelSample`` event (the daemon emits one a few times a
second for the page's sparklines and the ROS 2 reports), and ``names()`` the channel names.
It holds no I/O and reads no clock.
"""

from __future__ import annotations

from dataclasses import dataclass

from host.board.types import BoardEvent, BoardState, Reading, StreamItem
from host.events import ChannelReading, ChannelSample
from protocol.constants import EV_STATE, EV_TRIP, STATE_NAMES


@dataclass
class _Channel:
    name: str
    state: int = 0
    on: bool = False
    current_ma: float = 0.0


class BoardView:
    def __init__(self) -> None:
        self._channels: list[_Channel] = []
        self.latest: Reading | None = None
        self.input_mv: int | None = None  # the board's input voltage; None: not known

    def reset(self, state: BoardState) -> None:
        """Take the whole board (names, states, currents) from a fresh ``BoardState``."""
        self._channels = [_Channel(ch.name, ch.state, ch.physical, float(ch.current_ma))
                          for ch in state.channels]
        self.input_mv = _known(state.input_mv)

    def apply(self, item: StreamItem) -> None:
        """Fold one stream item in (link notices change nothing here)."""
        if isinstance(item, Reading):
            self.latest = item
            self.input_mv = _known(item.input_mv)
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

    def sample(self) -> ChannelSample:
        """Every channel now."""
        return ChannelSample(tuple(
            ChannelReading(i, c.name, c.on,
                           STATE_NAMES[c.state] if 0 <= c.state < len(STATE_NAMES)
                           else str(c.state), c.current_ma)
            for i, c in enumerate(self._channels)), self.input_mv)

    def names(self) -> list[str]:
        return [c.name for c in self._channels]


def _known(input_mv: int) -> int | None:
    """A board that does not measure its input says 0 mV (it could not run on 0 V)."""
    return input_mv if input_mv > 0 else None
