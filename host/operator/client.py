"""The client side of the daemon's operator socket (``dxboard quarantine``, ``dxboard hold``).

``ask(path, request)`` sends one request line to the running daemon's operator socket and
returns its reply, or raises ``UserError`` with what to do (no daemon there, a refusal in the
daemon's words). The default path is the one ``dxboard run`` uses by default:
``dxboard-journal.sock`` in the current directory (beside its journal).
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

from emulator.jsonlines import ask as ask_line
from host.errors import UserError

DEFAULT_SOCKET = Path("dxboard-journal.sock")
TIMEOUT_S = 30.0  # a quarantine switches the device off first


def default_socket(journal: Path) -> Path:
    """The operator socket ``dxboard run`` opens beside its journal."""
    return journal.with_suffix(".sock")


def ask(path: Path, request: dict[str, Any]) -> dict[str, Any]:
    try:
        reply = ask_line(path, request, TIMEOUT_S)
    except FileNotFoundError:
        raise UserError(f"{path}: no daemon's operator socket here",
                        "is `dxboard run` running? give its socket with --operator PATH "
                        "(it prints 'operator: PATH')") from None
    except PermissionError:
        raise UserError(f"{path}: not allowed to talk to this daemon",
                        "run as the user the daemon runs as") from None
    except OSError as exc:
        raise UserError(f"{path}: cannot reach the daemon: {exc}",
                        "is `dxboard run` still running?") from None
    if reply is None:
        raise UserError(f"{path}: the daemon did not answer", "is it still running?")
    if not reply.get("ok"):
        raise UserError(str(reply.get("error", "refused")))
    return reply
