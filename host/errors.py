"""The host's exception family, split by who must act.

``UserError`` is what a person can fix (a bad file, a wrong argument, an unreachable board):
the CLI prints it on one line with its hint and exits non-zero, without a traceback. Anything
else escaping a command is a bug in dxboard and is shown with its traceback.
"""

from __future__ import annotations


class DxboardError(Exception):
    """Base of every error the host raises on purpose."""


class UserError(DxboardError):
    """Something the user can fix: the message says what is wrong, ``hint`` what to do."""

    def __init__(self, message: str, hint: str = "") -> None:
        super().__init__(message)
        self.message = message
        self.hint = hint

    def __str__(self) -> str:
        return f"{self.message} ({self.hint})" if self.hint else self.message
