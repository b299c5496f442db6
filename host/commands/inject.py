"""Inject a fault into a running emulated board, or clear all faults, via its control endpoint.

``dxboard inject CONTROL_URL CHANNEL FAULT [key=value ...]`` or ``dxboard inject CONTROL_URL
clear``. CONTROL_URL is what ``dxboard emulate`` prints (``control://HOST:PORT``); a bare
``HOST:PORT`` works too. CHANNEL is ``board`` for board and link faults, else a channel number
or name. Faults: overcurrent amps=A, short, open_load, dropout period_s=S duty=D,
drift amps_per_s=A, hang permanent=true|false, stuck_on, stuck_off, sensor_offset amps=A,
sensor_gain factor=F, sensor_noise amps=A, sensor_stuck, brownout volts=V seconds=S,
wdt_reset, link_disconnect, link_freeze seconds=S, link_delay ms=M, link_corrupt rate=R.
The emulator checks names and values; anything it refuses, or an endpoint that does not
answer, is a one-line error (exit 2). This command speaks the endpoint's line-oriented JSON
protocol (see ``emulator/control.py``) and imports nothing of the emulator.
"""

from __future__ import annotations

import argparse
import json
import socket
from typing import Any

from host.errors import UserError

NAME = "inject"
HELP = "inject a fault into an emulated board (or clear all faults)"
TIMEOUT_S = 5.0


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("url", metavar="CONTROL_URL", help="control://HOST:PORT or HOST:PORT")
    parser.add_argument("channel", metavar="CHANNEL",
                        help="'board', a channel number or name; or 'clear' to clear all")
    parser.add_argument("fault", metavar="FAULT", nargs="?", help="fault name")
    parser.add_argument("params", metavar="key=value", nargs="*", help="fault parameters")


def parse_url(url: str) -> tuple[str, int]:
    rest = url.removeprefix("control://").rstrip("/")
    host, sep, port = rest.rpartition(":")
    if not sep or not host or not port.isdigit() or not 0 < int(port) < 65536:
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


def run(args: argparse.Namespace) -> int:
    if args.channel == "clear" and args.fault is None:
        reply = request(args.url, {"op": "clear"})
        print(f"cleared {reply.get('cleared', 0)} fault(s)")
        return 0
    if args.fault is None:
        raise UserError("missing FAULT", "dxboard inject URL CHANNEL FAULT [key=value ...]")
    params: dict[str, str] = {}
    for item in args.params:
        key, sep, value = item.partition("=")
        if not sep or not key:
            raise UserError(f"bad parameter {item!r}", "write parameters as key=value")
        params[key] = value
    channel: str | int = int(args.channel) if args.channel.isdigit() else args.channel
    if args.fault == "clear":
        reply = request(args.url, {"op": "clear", "channel": channel})
        print(f"cleared {reply.get('cleared', 0)} fault(s) on {args.channel}")
        return 0
    reply = request(args.url, {"op": "inject", "channel": channel, "fault": args.fault,
                               "params": params})
    shown = " ".join(f"{k}={v}" for k, v in reply.get("params", {}).items())
    print(f"injected {reply['fault']} on {reply['channel']} {shown}".rstrip())
    return 0
