"""Quarantines of the running daemon: list them, quarantine a component by hand, clear one.

``dxboard quarantine list``, ``dxboard quarantine add COMPONENT [--reason TEXT]``,
``dxboard quarantine clear COMPONENT``. A quarantined component is out of automatic repair: the
daemon put it in its safe state (a device switched off, a node stopped; never a protected one)
after its repair attempts ran out, or a person did with ``add``; it stays so across restarts
of the daemon (the journal keeps it) until a person clears it. Clearing gives it fresh attempts
(and, for a device the board latched for a short circuit, one switch-on). The command talks to
the running daemon over its operator socket (``--operator PATH``; default
``dxboard-journal.sock``, beside the default journal), which only the daemon's user can use.
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

from host.operator.client import DEFAULT_SOCKET, ask

NAME = "quarantine"
HELP = "list, set or clear the running daemon's quarantines"


def add_operator(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--operator", metavar="PATH", type=Path, default=DEFAULT_SOCKET,
                        help=f"the daemon's operator socket (default {DEFAULT_SOCKET})")
    parser.add_argument("--json", action="store_true", help="print the daemon's reply as JSON")


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("action", choices=("list", "add", "clear"))
    parser.add_argument("component", nargs="?", metavar="COMPONENT")
    parser.add_argument("--reason", default="", help="why (for add)")
    add_operator(parser)


def listing(reply: dict[str, object], which: str) -> None:
    entries = reply.get(which) or {}
    assert isinstance(entries, dict)
    if not entries:
        print(f"nothing {which}")
    for comp, why in sorted(entries.items()):
        print(f"{comp}: {why}")


def run(args: argparse.Namespace) -> int:
    from host.errors import UserError

    if args.action != "list" and not args.component:
        raise UserError(f"quarantine {args.action}: which component?",
                        f"dxboard quarantine {args.action} COMPONENT")
    op = {"list": "list", "add": "quarantine", "clear": "clear"}[args.action]
    reply = ask(args.operator, {"op": op, "component": args.component, "reason": args.reason})
    if args.json:
        print(json.dumps(reply))
    elif op == "list":
        listing(reply, "quarantined")
    elif op == "quarantine":
        print(f"{args.component} quarantined; safe state: {reply.get('safe_state') or 'as is'}")
    else:
        also = [c for c in reply.get("cleared", []) if c != args.component]
        with_ = f", with {', '.join(also)} (quarantined with it)" if also else ""
        print(f"{args.component}: quarantine cleared{with_}" if reply.get("changed")
              else f"{args.component} was not quarantined")
    return 0
