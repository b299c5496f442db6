"""Errors of the transports and the board client, split by who must act (STYLE.md 4).

Everything here is a ``UserError``: a person can fix it (a mistyped URL, a board that is off
or unplugged, a wrong key, a firmware too old or too new), so the CLI prints it on one line
with what to do next. ``BoardUnreachable`` covers every way a link fails (refused, vanished,
silent); ``RequestTimeout`` is also a ``TimeoutError``, as python-can's ``CanTimeoutError``
is, so ``except TimeoutError`` catches it. ``BoardRefused`` carries the board's E_* code.
"""

from __future__ import annotations

from host.errors import UserError


class TransportError(UserError):
    """Base of every error raised by a transport or the board client."""


class BadUrl(TransportError):
    """The board URL cannot be used: unknown scheme, missing port, bad query value."""


class BoardUnreachable(TransportError):
    """The board cannot be reached, or the link to it was lost."""


class LinkLost(BoardUnreachable):
    """The link closed or broke while in use (the board rebooted, a cable was pulled)."""


class RequestTimeout(BoardUnreachable, TimeoutError):
    """The board did not answer a request in time."""


class UnexpectedDevice(BoardUnreachable):
    """The device at the URL answers, but not as the URL says it should (a Modbus device
    without the registers of the map, a unit id it does not serve, no channels)."""


class NotSupported(TransportError):
    """The transport cannot do this (for instance: configuration over CAN)."""


class VersionMismatch(TransportError):
    """The board speaks another protocol version than this host."""


class BoardRefused(TransportError):
    """The board answered a request with ERROR; ``code`` is the E_* code."""

    def __init__(self, message: str, hint: str = "", code: int = 0) -> None:
        super().__init__(message, hint)
        self.code = code


class AuthRefused(BoardRefused):
    """The board refused the authentication tag: the key is wrong, or missing."""


class KeyMissing(TransportError):
    """An authenticated command was asked for without a key: nothing was sent."""


class BadChannel(TransportError):
    """A channel number or name the board does not have."""


class BadSetting(TransportError):
    """A configuration field the board does not have, or a value outside its range."""


class ReadbackMismatch(TransportError):
    """The board acknowledged a command but its read-back disagrees with what was asked."""
