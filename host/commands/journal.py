"""Read a journal file: ``dxboard journal FILE [--tail N] [--kind K] [--json]``.

Prints the last N entries (20 by default) of the journal the daemon writes (``dxboard run
--journal FILE``), oldest first, one line each: id, wall time (UTC), kind and a short summary;
``--kind`` keeps one kind (observation, diagnosis, plan, action, board_event, telemetry, note;
may be repeated); ``--json`` prints one JSON object a line (``{"id", "kind", "wall", "mono",
"data"}``) for scripts. The file is only read, and may be read while the daemon writes it.
"""

from __future__ import annotations

import argparse
import json
from datetime import UTC, datetime

NAME = "journal"
HELP = "show the last entries of a journal file"


def add_arguments(parser: argparse.ArgumentParser) -> None:
    from host.events import Kind

    parser.add_argument("file", metavar="FILE", help="journal file (SQLite)")
    parser.add_argument("--tail", type=int, default=20, metavar="N",
                        help="how many of the last entries to show (default: 20)")
    parser.add_argument("--kind", action="append", choices=[k.value for k in Kind],
                        metavar="K", help="only entries of this kind (may be repeated)")
    parser.add_argument("--json", action="store_true", help="one JSON object a line")


def run(args: argparse.Namespace) -> int:
    from host.errors import UserError
    from host.journal.store import JournalReader
    from host.journal.summary import summarize

    if args.tail < 0:
        raise UserError(f"--tail {args.tail} is negative", "give --tail 0 or more")
    with JournalReader(args.file) as reader:
        entries = reader.tail(args.tail, kind=args.kind)
    for entry in entries:
        if args.json:
            print(json.dumps(entry.to_json(), separators=(",", ":")))
        else:
            when = datetime.fromtimestamp(entry.wall, UTC).strftime("%Y-%m-%d %H:%M:%S.%f")[:-3]
            print(f"{entry.id:>8}  {when}  {entry.kind.value:<11}  {summarize(entry.payload)}")
    return 0
