"""Holds of the running daemon: leave a component alone while a person works on it.

``dxboard hold list``, ``dxboard hold add COMPONENT [--reason TEXT]``, ``dxboard hold release
COMPONENT``. While a component is held no repair touches it — no power-cycle, no restart, no
quarantine — whatever the diagnosis says; the daemon still observes and reports it. A board
channel switched off by a command the daemon did not send (``dxboard board URL off CH`` by a
person) is held the same way until it is switched on again. Holds last across restarts of the
daemon until released. Talks to the running daemon over its operator socket (``--operator``,
as for ``dxboard quarantine``).
"""

from __future__ import annotations

import argparse
import json

from host.commands.quarantine import add_operator, listing
from host.operator.client import ask

NAME = "hold"
HELP = "list, set or release the running daemon's holds (maintenance)"


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("action", choices=("list", "add", "release"))
    parser.add_argument("component", nargs="?", metavar="COMPONENT")
    parser.add_argument("--reason", default="", help="why (for add)")
    add_operator(parser)


def run(args: argparse.Namespace) -> int:
    from host.errors import UserError

    if args.action != "list" and not args.component:
        raise UserError(f"hold {args.action}: which component?",
                        f"dxboard hold {args.action} COMPONENT")
    op = {"list": "list", "add": "hold", "release": "release"}[args.action]
    reply = ask(args.operator, {"op": op, "component": args.component, "reason": args.reason})
    if args.json:
        print(json.dumps(reply))
    elif op == "list":
        listing(reply, "held")
    elif op == "hold":
        print(f"{args.component} held: no repair touches it" if reply.get("changed")
              else f"{args.component} was already held")
    else:
        print(f"{args.component} released" if reply.get("changed")
              else f"{args.component} was not held")
    return 0
