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

from host.errors import UserError
from host.launch.control import request

NAME = "inject"
HELP = "inject a fault into an emulated board (or clear all faults)"


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("url", metavar="CONTROL_URL", help="control://HOST:PORT or HOST:PORT")
    parser.add_argument("channel", metavar="CHANNEL",
                        help="'board', a channel number or name; or 'clear' to clear all")
    parser.add_argument("fault", metavar="FAULT", nargs="?", help="fault name")
    parser.add_argument("params", metavar="key=value", nargs="*", help="fault parameters")


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
