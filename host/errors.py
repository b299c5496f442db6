"""The host's exception family, split by who is at fault (house style point 4, h11's
Local/Remote ProtocolError).

Every error the host raises on purpose is a ``DxboardError`` with a ``message`` (what is wrong,
naming the file, the line, the value or the peer) and a ``hint`` (what to do next). Two kinds:

- ``UserError`` — local: what a person gave dxboard is wrong (a bad file, a wrong argument, a
  wrong key, a request the transport cannot carry). Fixing the input fixes it.
- ``RemoteError`` — remote: the other side failed (a board that does not answer or refuses, a
  link that broke, a switch that did not move, a process that would not start). The input was
  fine; the robot, the link or the peer needs a look, or a retry may do.

Code that keeps going on remote failures (the daemon's board task reconnects) catches
``RemoteError`` and lets a ``UserError`` stop it. The CLI prints either as one line with its
hint, exit code 2, without a traceback (``-v`` adds it); anything else escaping a command is a
bug in dxboard and is shown with its traceback.
"""

from __future__ import annotations


class DxboardError(Exception):
    """Base of every error the host raises on purpose: ``message`` and ``hint``."""

    def __init__(self, message: str = "", hint: str = "") -> None:
        super().__init__(message)
        self.message = message
        self.hint = hint

    def __str__(self) -> str:
        return f"{self.message} ({self.hint})" if self.hint else self.message


class UserError(DxboardError):
    """Local: something the user gave is wrong; the message says what, ``hint`` what to do."""


class RemoteError(DxboardError):
    """Remote: the board, the link or another peer failed; the message says which and how."""
