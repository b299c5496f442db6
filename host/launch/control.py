"""A client of the emulated board's control endpoint (``control://HOST:PORT``).

One JSON object per line each way (the protocol is ``emulator/control.py``'s; nothing of the
emulator is imported): ``request(url, {"op": "inject", ...})`` sends one request and returns the
reply, or raises ``UserError`` naming what went wrong (unreachable, not a control endpoint, a
refusal with the emulator's own words). ``dxboard inject``, the experiments and the launcher's
questions to the emulated robot (its devices' boot times) all go through it.
"""

from __future__ import annotations

import asyncio
import json
import socket
from typing import Any

from host.errors import UserError

TIMEOUT_S = 5.0


def parse_url(url: str) -> tuple[str, int]:
    rest = url.removeprefix("control://").rstrip("/")
    host, sep, port = rest.rpartition(":")
    if ("://" in rest or "/" in host or not sep or not host or not port.isdigit()
            or not 0 < int(port) < 65536):
        raise UserError(f"bad control URL {url!r}",
                        "give control://HOST:PORT as printed by `dxboard emulate`, or HOST:PORT")
    return host.strip("[]"), int(port)


def request(url: str, req: dict[str, Any]) -> dict[str, Any]:
    """Send one request line and return the reply; ``UserError`` if the endpoint fails."""
    host, port = parse_url(url)
    try:
        with socket.create_connection((host, port), timeout=TIMEOUT_S) as sock:
            sock.sendall(json.dumps(req).encode() + b"\n")
            buf = b""
            while not buf.endswith(b"\n"):
                chunk = sock.recv(65536)
                if not chunk:
                    break
                buf += chunk
    except OSError as exc:
        raise UserError(f"cannot reach the control endpoint {host}:{port}: {exc}",
                        "is `dxboard emulate` running? use the control URL it printed") from exc
    try:
        reply = json.loads(buf)
    except ValueError as exc:
        raise UserError(f"{host}:{port} is not a dxboard control endpoint",
                        "use the control URL, not the board URL") from exc
    if not isinstance(reply, dict):
        raise UserError(f"{host}:{port} is not a dxboard control endpoint")
    if not reply.get("ok"):
        raise UserError(str(reply.get("error", "refused")))
    return reply


async def arequest(url: str, req: dict[str, Any]) -> dict[str, Any]:
    """``request`` without blocking the event loop."""
    return await asyncio.to_thread(request, url, req)
