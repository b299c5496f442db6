"""A client of the emulated board's control endpoint (``control://HOST:PORT``).

One JSON object per line each way (the protocol is ``emulator/control.py``'s; of the emulator
only the wire helper ``emulator.jsonlines`` is imported): ``request(url, {"op": "inject",
...})`` sends one request and returns the reply, or raises ``UserError`` naming what went
wrong (unreachable, not a control endpoint, a refusal with the emulator's own words).
``dxboard inject``, the experiments and the launcher's questions to the emulated robot (its
devices' boot times) all go through it.
"""

from __future__ import annotations

import asyncio
from typing import Any

from emulator.jsonlines import ask
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
        reply = ask((host, port), req, TIMEOUT_S)
    except OSError as exc:
        raise UserError(f"cannot reach the control endpoint {host}:{port}: {exc}",
                        "is `dxboard emulate` running? use the control URL it printed") from exc
    if reply is None:
        raise UserError(f"{host}:{port} is not a dxboard control endpoint",
                        "use the control URL, not the board URL")
    if not reply.get("ok"):
        raise UserError(str(reply.get("error", "refused")))
    return reply


async def arequest(url: str, req: dict[str, Any]) -> dict[str, Any]:
    """``request`` without blocking the event loop."""
    return await asyncio.to_thread(request, url, req)
