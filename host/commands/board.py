"""Talk to one board: status, switching, power cycles, a live view of currents, configuration.

``dxboard board URL ACTION``, URL as in ARCHITECTURE.md (``tcp://H:P``, ``serial:///dev/X``,
``modbus+tcp://H:P``, ``can://virtual/ch0``, ``tug://H:P``). Actions: ``status`` (a table:
channel, name, state, current, faults), ``on CH`` / ``off CH [--force]`` / ``cycle CH
[--off-s S]`` / ``clear CH`` (CH a number or a name; ``clear all``), ``watch`` (a live table of
currents refreshed in place; ``--count N`` stops after N readings), ``config get [CH|board]``,
``config set CH|board key=value ...`` and ``config save``. The key (needed to actuate) comes
from ``$DXBOARD_KEY`` or ``--key-file``, never from the command line. ``--json`` prints JSON
for scripts (``watch``: one object per line). A board that cannot be reached, refuses the key,
speaks another version or stops answering is a one-line error and exit code 2.
"""

from __future__ import annotations

import argparse
import asyncio
import json
import logging
import sys
from typing import Any

NAME = "board"
HELP = "status, switch, power-cycle, watch or configure one board (by URL)"

log = logging.getLogger(__name__)


def _common(p: argparse.ArgumentParser, json_opt: bool = True) -> None:
    p.add_argument("--key-file", metavar="FILE",
                   help="file with the key as hex (else $DXBOARD_KEY)")
    p.add_argument("--timeout", type=float, default=2.0, metavar="S", help="request timeout (s)")
    if json_opt:
        p.add_argument("--json", action="store_true", help="print JSON")


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("url", metavar="URL", help="board URL, e.g. tcp://192.168.0.7:7000")
    sub = parser.add_subparsers(dest="action", metavar="ACTION")
    sub.required = True
    _common(sub.add_parser("status", help="a table of every channel"))
    for name, helptext in (("on", "switch a channel on"), ("off", "switch a channel off")):
        p = sub.add_parser(name, help=helptext)
        p.add_argument("channel", metavar="CH", help="channel number or name")
        p.add_argument("--force", action="store_true", help="also a protected channel")
        _common(p)
    p = sub.add_parser("cycle", help="power-cycle a channel (off, wait, on)")
    p.add_argument("channel", metavar="CH")
    p.add_argument("--off-s", type=float, default=1.0, metavar="S", help="off time (s)")
    p.add_argument("--force", action="store_true", help="also a protected channel")
    _common(p)
    p = sub.add_parser("clear", help="clear a latched channel's faults ('all': every channel)")
    p.add_argument("channel", metavar="CH")
    _common(p)
    p = sub.add_parser("watch", help="a live table of currents")
    p.add_argument("--rate", type=int, default=5, metavar="HZ", help="readings per second")
    p.add_argument("--count", type=int, default=0, metavar="N", help="stop after N readings")
    _common(p)
    p = sub.add_parser("config", help="get, set or save the configuration")
    p.add_argument("op", choices=["get", "set", "save"])
    p.add_argument("target", nargs="?", default="board", metavar="CH|board")
    p.add_argument("values", nargs="*", metavar="key=value")
    _common(p)


def parse_value(text: str) -> Any:
    """``key=value`` values: integers, true/false, comma lists of integers, else text."""
    low = text.lower()
    if low in ("true", "false"):
        return low == "true"
    try:
        return int(text, 0)
    except ValueError:
        pass
    if "," in text:
        try:
            return [int(x, 0) for x in text.split(",") if x]
        except ValueError:
            pass
    return text


def _assignments(values: list[str]) -> dict[str, Any]:
    from host.errors import UserError

    out: dict[str, Any] = {}
    for item in values:
        key, sep, value = item.partition("=")
        if not sep or not key:
            raise UserError(f"{item!r} is not key=value", "e.g. rated_ma=1500")
        out[key] = parse_value(value)
    if not out:
        raise UserError("config set needs key=value pairs", "e.g. config set hokuyo rated_ma=1500")
    return out


def _faults(live: list[str], sticky: list[str]) -> str:
    parts = list(live) + [f"({s})" for s in sticky if s not in live]
    return ",".join(parts) or "-"


def format_status(info: dict[str, Any], state: dict[str, Any]) -> str:
    lines = [f"board {info['board_id']} (firmware {info['firmware']}, boot {info['boot_id']:08x},"
             f" up {state['uptime_ms'] / 1000:.1f} s) via {info['url']}",
             f"input {state['input_mv'] / 1000:.2f} V, total {state['total_ma'] / 1000:.2f} A, "
             f"flags {','.join(state['board_flags']) or '-'}, config {state['config_status']}",
             f"{'CH':>2}  {'NAME':<16} {'STATE':<8} {'CURRENT':>9}  FAULTS"]
    low = False
    for c in state["channels"]:
        live = [f for f in c["live_faults"] if f != "low"]  # low: how it was read, no fault
        faults = _faults(live, c["sticky_faults"])
        current = f"{c['current_ma'] / 1000:>7.3f} A"
        if "low" in c["live_faults"]:
            low, current = True, f"{'low *':>9}"
        lines.append(f"{c['channel']:>2}  {c['name']:<16} {c['state']:<8} {current}  {faults}")
    if low:
        lines.append("* low, not measured: below the range the board's current sense measures "
                     "(a small load, not an open one)")
    return "\n".join(lines)


def format_watch(names: list[str], reading: dict[str, Any]) -> list[str]:
    lines = [f"seq {reading['seq']}  up {reading['uptime_ms'] / 1000:.1f} s  "
             f"input {reading['input_mv'] / 1000:.2f} V  missed {reading['missed']}"]
    for i, ma in enumerate(reading["currents_ma"]):
        on = "on " if reading["on_mask"] >> i & 1 else "off"
        fault = "FAULT" if reading["fault_mask"] >> i & 1 else ""
        lines.append(f"{i:>2}  {names[i] if i < len(names) else '':<16} {on} "
                     f"{ma / 1000:>7.3f} A  {fault}")
    return lines


async def _watch(client: Any, args: argparse.Namespace) -> None:
    from host.board.types import Reading

    names = await client.channel_names()
    shown = 0
    count = 0
    live = sys.stdout.isatty() and not args.json
    async for item in client.subscribe(args.rate):
        if isinstance(item, Reading):
            count += 1
            if args.json:
                print(json.dumps(item.to_dict()), flush=True)
            else:
                lines = format_watch(names, item.to_dict())
                if live and shown:
                    sys.stdout.write(f"\x1b[{shown}F\x1b[J")
                sys.stdout.write("\n".join(lines) + "\n")
                sys.stdout.flush()
                shown = len(lines)
        else:
            note = {"notice": type(item).__name__}
            log.warning("%s: %s", args.url, item)
            if args.json:
                print(json.dumps(note), flush=True)
            else:
                shown = 0
                print(f"-- {type(item).__name__} --", flush=True)
        if args.count and count >= args.count:
            return


async def _run(args: argparse.Namespace, key: bytes | None) -> int:
    from host.board.client import BoardClient

    client = BoardClient(args.url, key, timeout_s=args.timeout, reconnect=args.action == "watch")
    await client.connect()
    try:
        return await _act(client, args)
    finally:
        await client.close()


async def _act(client: Any, args: argparse.Namespace) -> int:
    action = args.action
    if action == "status":
        info = client.info.to_dict()
        state = (await client.state()).to_dict()
        if args.json:
            print(json.dumps({"board": info, "state": state}))
        else:
            print(format_status(info, state))
        return 0
    if action in ("on", "off", "cycle", "clear"):
        if action == "cycle":
            res = await client.power_cycle(args.channel, args.off_s, args.force)
        elif action == "clear":
            res = await client.clear(args.channel)
        else:
            res = await client.switch(args.channel, action == "on", args.force)
        if args.json:
            print(json.dumps({"ok": True, "action": action,
                              "result": res.to_dict() if res else None}))
        elif res is None:
            print("cleared every channel")
        else:
            print(f"{action}: channel {res.channel} ({res.name}) is now {res.state_name}, "
                  f"switch reads back {'on' if res.physical else 'off'}")
        return 0
    if action == "watch":
        await _watch(client, args)
        return 0
    return await _config(client, args)


async def _config(client: Any, args: argparse.Namespace) -> int:
    board = args.target == "board"
    if args.op == "save":
        await client.configurator.save_config()
        print(json.dumps({"ok": True, "saved": True}) if args.json else "configuration saved")
        return 0
    if args.op == "get":
        cfg = await (client.configurator.get_board_config() if board
                     else client.configurator.get_channel_config(args.target))
    else:
        fields = _assignments(args.values)
        cfg = await (client.configurator.set_board_config(**fields) if board
                     else client.configurator.set_channel_config(args.target, **fields))
    if args.json:
        print(json.dumps(cfg))
    else:
        width = max(len(k) for k in cfg)
        for k, v in cfg.items():
            print(f"{k:<{width}}  {v}")
        if args.op == "set":
            print("(set and read back; not saved: `config save` persists it)")
    return 0


def run(args: argparse.Namespace) -> int:
    from host.board.keys import load_key

    key = load_key(args.key_file)
    return asyncio.run(_run(args, key))
