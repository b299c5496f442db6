"""The host's view of one board: ``BoardClient`` and the values it hands out.

``host.board.client`` is the async client (connect, state, subscribe, switch, power-cycle,
clear, configure), whose link is judged in ``host.board.link`` (silence, keepalive, reconnect,
reboot detection); ``host.board.types`` the typed values
(``BoardInfo``, ``BoardState``, ``Reading``, ``BoardEvent``, link notices); ``host.board.keys``
where the key comes from. Errors are those of ``host.transports.errors``.
"""

from host.board.client import BoardClient
from host.board.types import (
    BoardEvent,
    BoardInfo,
    BoardState,
    ChannelState,
    LinkDown,
    LinkUp,
    Reading,
    Rebooted,
    StreamItem,
    SwitchResult,
)

__all__ = ["BoardClient", "BoardEvent", "BoardInfo", "BoardState", "ChannelState", "LinkDown",
           "LinkUp", "Reading", "Rebooted", "StreamItem", "SwitchResult"]
