"""Errors of the transports and the board client, split by who is at fault (STYLE.md 4).

``TransportError`` is the family. Local ones (``UserError``: the person fixes the input) are a
board URL that cannot be used (``BadUrl``), a request the transport cannot carry
(``NotSupported``), a channel or a value out of range (``BadChannel``, ``BadRequest``; a
configuration field or value: ``BadSetting``), and an authenticated command without a key
(``KeyMissing``). Remote ones (``RemoteError``: the board or the link) are every way a link
fails (``BoardUnreachable``; ``LinkLost`` while in use; a device that answers but not as the
URL says: ``UnexpectedDevice``; ``RequestTimeout``, also a ``TimeoutError`` as python-can's
``CanTimeoutError`` is, so ``except TimeoutError`` catches it), a board speaking another
protocol version (``VersionMismatch``), a board that refused a request (``BoardRefused``, with
the board's E_* code; ``AuthRefused`` for a bad or missing key), a switch that did not move
(``ReadbackMismatch``) and a reply that contradicts the board's HELLO (``BadReply``). Garbage
from the wire is never raised as a local error.
"""

from __future__ import annotations

from host.errors import DxboardError, RemoteError, UserError


class TransportError(DxboardError):
    """Base of every error raised by a transport or the board client."""


class LocalTransportError(TransportError, UserError):
    """The request or the URL is wrong: nothing was sent."""


class RemoteTransportError(TransportError, RemoteError):
    """The board or the link failed, or the board refused."""


class BadUrl(LocalTransportError):
    """The board URL cannot be used: unknown scheme, missing port, bad query value."""


class NotSupported(LocalTransportError):
    """The transport cannot do this (for instance: configuration over CAN)."""


class BadChannel(LocalTransportError):
    """A channel number or name the board does not have."""


class BadRequest(LocalTransportError):
    """A value out of range (a rate, an off time) or a setting the board does not have."""


class BoardUnreachable(RemoteTransportError):
    """The board cannot be reached, or the link to it was lost."""


class LinkLost(BoardUnreachable):
    """The link closed or broke while in use (the board rebooted, a cable was pulled)."""


class RequestTimeout(BoardUnreachable, TimeoutError):
    """The board did not answer a request in time."""


class UnexpectedDevice(BoardUnreachable):
    """The device at the URL answers, but not as the URL says it should (a Modbus device
    without the registers of the map, a unit id it does not serve, no channels)."""


class VersionMismatch(RemoteTransportError):
    """The board speaks another protocol version than this host."""


class BoardRefused(RemoteTransportError):
    """The board answered a request with ERROR; ``code`` is the E_* code."""

    def __init__(self, message: str, hint: str = "", code: int = 0) -> None:
        super().__init__(message, hint)
        self.code = code


class AuthRefused(BoardRefused):
    """The board refused the authentication tag: the key is wrong, or missing."""


class KeyMissing(LocalTransportError):
    """An authenticated command was asked for without a key: nothing was sent."""


class BadSetting(BadRequest):
    """A configuration field the board does not have, or a value outside its range."""


class ReadbackMismatch(RemoteTransportError):
    """The board acknowledged a command but its read-back disagrees with what was asked."""


class BadReply(RemoteTransportError):
    """The board's reply contradicts what it said before (a STATE whose channels are not the
    ones its HELLO announced): a lying or corrupted frame; nothing is believed from it."""
