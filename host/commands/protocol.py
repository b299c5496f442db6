"""Decode dxboard frames given in hex, as a person debugging a capture would.

``dxboard protocol decode HEX...`` feeds the bytes to a host-side (or, with ``--as-board``,
a board-side) codec and prints one line per event: each message with its fields, each
error with its code and text. The exit code is 0 when every event is a message, 2 (with one
line on stderr) when the input held anything that is not a whole, valid frame.
Authenticated frames are decoded without checking their tag as the host; decoded as the board
(which has no key here) they show as error 200, authentication required.
"""

from __future__ import annotations

import argparse
import json
import sys

from host.errors import UserError

NAME = "protocol"
HELP = "decode protocol frames given in hex"


def add_arguments(parser: argparse.ArgumentParser) -> None:
    sub = parser.add_subparsers(dest="action", metavar="ACTION", required=True)
    dec = sub.add_parser("decode", help="decode frames given in hex (spaces allowed)")
    dec.add_argument("hex", nargs="+", help="frame bytes in hex; '-' reads them from stdin")
    dec.add_argument(
        "--as-board", action="store_true", help="decode as the board would (host messages)"
    )
    dec.add_argument("--json", action="store_true", help="one JSON object per event")


def _read_hex(parts: list[str]) -> bytes:
    text = sys.stdin.read() if parts == ["-"] else " ".join(parts)
    cleaned = "".join(text.split())
    try:
        return bytes.fromhex(cleaned)
    except ValueError:
        raise UserError(
            f"not hex: {cleaned[:40]!r}", "give the frame bytes as hex digits, e.g. db5801..."
        ) from None


def run(args: argparse.Namespace) -> int:
    from protocol.connection import BOARD, HOST, Connection
    from protocol.constants import E_NOT_A_REQUEST
    from protocol.framing import BadFrame
    from protocol.messages import Hello, Message

    data = _read_hex(args.hex)
    conn = Connection(BOARD if args.as_board else HOST)
    if args.as_board:
        # A board decodes host messages only within a session; start one without a key, so
        # actuation frames show as "authentication required" rather than being trusted.
        conn.send(Hello(1, "decoder", "", 0, 0, 0, bytes(16), 0, 0))
    conn.receive_data(data)
    conn.receive_data(b"")
    errors = []
    for ev in conn.events():
        if isinstance(ev, Message):
            if args.json:
                out = {"message": type(ev).__name__, "req_id": ev.req_id, **ev.to_dict()}
                print(json.dumps(out))
            else:
                print(repr(ev))
        elif isinstance(ev, BadFrame):
            errors.append(ev)
            if args.json:
                print(json.dumps({"error": ev.code, "text": ev.text, "skipped": ev.skipped}))
            else:
                print(f"error {ev.code}: {ev.text} ({ev.skipped} bytes skipped)")
    if errors:
        first = errors[0]
        hint = "give whole frames as hex, from the start marker db58 to the CRC"
        if first.code == E_NOT_A_REQUEST:
            hint = ("a message of the other direction: decode it without --as-board"
                    if args.as_board else "a host's message: decode it with --as-board")
        raise UserError(f"not every byte is part of a valid frame ({len(errors)} error(s); "
                        f"the first: error {first.code}, {first.text})", hint)
    return 0
