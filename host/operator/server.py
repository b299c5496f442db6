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
line that is not JSON); a bad line changes nothing. ``Operator`` is what the server calls: the
repair service implements it.
"""

from __future__ import annotations

import asyncio
import contextlib
import json
import logging
import os
from pathlib import Path
from typing import Any, Protocol

log = logging.getLogger(__name__)

MAX_LINE = 4096


class Operator(Protocol):
    def components(self) -> list[str]: ...

    def listing(self) -> dict[str, dict[str, str]]: ...

    async def quarantine(self, component: str, reason: str, by: str) -> str: ...

    async def clear(self, component: str, by: str) -> list[str]: ...

    def hold(self, component: str, reason: str, by: str) -> bool: ...

    def release(self, component: str, by: str) -> bool: ...


async def handle(op: Operator, line: bytes) -> dict[str, Any]:
    """The reply to one request line."""
    try:
        req = json.loads(line)
    except (ValueError, UnicodeDecodeError):
        return {"ok": False, "error": "not a JSON object on one line"}
    if not isinstance(req, dict):
        return {"ok": False, "error": "not a JSON object on one line"}
    kind = req.get("op")
    if kind == "list":
        return {"ok": True, **op.listing()}
    if kind not in ("quarantine", "clear", "hold", "release"):
        return {"ok": False, "error": f"unknown op {kind!r} (list, quarantine, clear, hold, "
                                      "release)"}
    comp = req.get("component")
    if not isinstance(comp, str) or comp not in op.components():
        return {"ok": False, "error": f"no component {comp!r}; the robot's components: "
                                      + ", ".join(sorted(op.components()))}
    reason = str(req.get("reason") or "")
    by = "person"
    if kind == "quarantine":
        return {"ok": True, "safe_state": await op.quarantine(comp, reason or "by hand", by)}
    if kind == "clear":
        cleared = await op.clear(comp, by)
        return {"ok": True, "changed": bool(cleared), "cleared": cleared}
    if kind == "hold":
        return {"ok": True, "changed": op.hold(comp, reason or "maintenance", by)}
    return {"ok": True, "changed": op.release(comp, by)}


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
                self._client, path=str(self.path), limit=MAX_LINE)
        finally:
            os.umask(old)
        self.path.chmod(0o600)

    async def _client(self, reader: asyncio.StreamReader, writer: asyncio.StreamWriter) -> None:
        try:
            while True:
                try:
                    line = await reader.readuntil(b"\n")
                except (asyncio.LimitOverrunError, ValueError):
                    writer.write(b'{"ok": false, "error": "line too long"}\n')
                    break
                except asyncio.IncompleteReadError:
                    break
                try:
                    reply = await handle(self.operator, line)
                except Exception as exc:  # the daemon stays up; the person hears why
                    log.exception("operator request failed")
                    reply = {"ok": False, "error": f"failed: {exc}"}
                writer.write(json.dumps(reply).encode() + b"\n")
                await writer.drain()
        except ConnectionError:
            pass
        finally:
            writer.close()

    async def close(self) -> None:
        if self._server is not None:
            self._server.close()
            await self._server.wait_closed()
            self._server = None
        with contextlib.suppress(FileNotFoundError):
            self.path.unlink()
