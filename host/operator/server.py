"""The daemon's operator endpoint: a person lists, sets and clears quarantines and holds.

Local only, never on the network: a Unix domain socket (``dxboard run --operator PATH``, by
default beside the journal, ``dxboard-journal.sock``), created readable and writable by its
owner only (mode 0600), so only the user the daemon runs as (and root) can talk to it — the
same people who can read its journal and kill it. One JSON object per line each way, one reply
per request, in order:

    {"op": "list"}                                   -> {"ok": true, "quarantined": {C: why},
                                                         "held": {C: why}}
    {"op": "quarantine", "component": C, "reason": R} -> {"ok": true, "safe_state": "..."}
    {"op": "clear", "component": C}                   -> {"ok": true, "cleared": [C, ...]}
    {"op": "hold", "component": C, "reason": R}       -> {"ok": true}
    {"op": "release", "component": C}                 -> {"ok": true}

Errors are ``{"ok": false, "error": "..."}`` with words for a person (an unknown component, a
line that is not JSON); a bad line changes nothing. The wire is ``emulator.jsonlines``'s.
``Operator`` is what the server calls: the repair service implements it.
"""

from __future__ import annotations

import asyncio
import contextlib
import os
from pathlib import Path
from typing import Any, Protocol

from emulator.jsonlines import Lines

MAX_LINE = 4096
BY = "person"


class Operator(Protocol):
    def components(self) -> list[str]: ...

    def listing(self) -> dict[str, dict[str, str]]: ...

    async def quarantine(self, component: str, reason: str, by: str) -> str: ...

    async def clear(self, component: str, by: str) -> list[str]: ...

    def hold(self, component: str, reason: str, by: str) -> bool: ...

    def release(self, component: str, by: str) -> bool: ...


def _component(op: Operator, req: dict[str, Any]) -> str:
    comp = req.get("component")
    if not isinstance(comp, str) or comp not in op.components():
        raise ValueError(f"no component {comp!r}; the robot's components: "
                         + ", ".join(sorted(op.components())))
    return comp


async def _quarantine(op: Operator, req: dict[str, Any]) -> dict[str, Any]:
    comp = _component(op, req)
    reason = str(req.get("reason") or "")
    return {"ok": True, "safe_state": await op.quarantine(comp, reason or "by hand", BY)}


async def _clear(op: Operator, req: dict[str, Any]) -> dict[str, Any]:
    cleared = await op.clear(_component(op, req), BY)
    return {"ok": True, "changed": bool(cleared), "cleared": cleared}


def _hold(op: Operator, req: dict[str, Any]) -> dict[str, Any]:
    comp = _component(op, req)
    reason = str(req.get("reason") or "")
    return {"ok": True, "changed": op.hold(comp, reason or "maintenance", BY)}


def lines(op: Operator) -> Lines:
    """The operator socket's requests."""
    return Lines({
        "list": lambda req, conn: {"ok": True, **op.listing()},
        "quarantine": lambda req, conn: _quarantine(op, req),
        "clear": lambda req, conn: _clear(op, req),
        "hold": lambda req, conn: _hold(op, req),
        "release": lambda req, conn: {"ok": True,
                                      "changed": op.release(_component(op, req), BY)},
    }, max_line=MAX_LINE)


class OperatorServer:
    def __init__(self, operator: Operator, path: Path) -> None:
        self.operator = operator
        self.path = path
        self._server: asyncio.Server | None = None

    async def start(self) -> None:
        with contextlib.suppress(FileNotFoundError):
            if self.path.is_socket():
                self.path.unlink()  # a stale socket of a daemon that died
        old = os.umask(0o177)
        try:
            self._server = await asyncio.start_unix_server(
                lines(self.operator).serve, path=str(self.path), limit=MAX_LINE)
        finally:
            os.umask(old)
        self.path.chmod(0o600)

    async def close(self) -> None:
        if self._server is not None:
            self._server.close()
            await self._server.wait_closed()
            self._server = None
        with contextlib.suppress(FileNotFoundError):
            self.path.unlink()
