"""The host's view of one board: ``BoardClient`` and the values it hands out.

``host.board.client`` is the async client, composed of the parts it holds: its link
(``host.board.link``: connection, greeting, request/reply, keepalive, silence, reconnect,
reboot detection; ``requests`` and ``fanout`` its halves), its channel names
(``host.board.channels``), its actuator (``host.board.actuate``: switch, power-cycle, clear) and
its configurator (``host.board.configure``). ``host.board.backoff`` is the one reconnect policy
(the link's and the daemon's); ``host.board.types`` the typed values (``BoardInfo``,
``BoardState``, ``Reading``, ``BoardEvent``, link notices); ``host.board.keys`` where the key
comes from. Errors are those of ``host.transports.errors``.
"""

from typing import TYPE_CHECKING, Any

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

if TYPE_CHECKING:
    from host.board.client import BoardClient

__all__ = ["BoardClient", "BoardEvent", "BoardInfo", "BoardState", "ChannelState", "LinkDown",
           "LinkUp", "Reading", "Rebooted", "StreamItem", "SwitchResult"]


def __getattr__(name: str) -> Any:
    """``BoardClient`` is loaded on first use (PEP 562): the typed values alone do not bring
    the client, asyncio and the transports in (``dxboard plan`` reads the board's devices)."""
    if name == "BoardClient":
        from host.board.client import BoardClient

        return BoardClient
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
