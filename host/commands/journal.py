"""Read a journal file: ``dxboard journal FILE [--tail N] [--kind K] [--run ID | --runs]
[--json]``.

Prints the last N entries (20 by default) of the journal the daemon writes (``dxboard run
--journal FILE``), oldest first, one line each: id, wall time (UTC), kind and a short summary;
``--kind`` keeps one kind (observation, diagnosis, plan, action, board_event, telemetry, note,
link, repair, quarantine, hold, run; may be repeated); ``--json`` prints one JSON object a line
(``{"id", "kind", "wall", "mono", "data"}``) for scripts. A journal holds every daemon run that
wrote to it (``make run`` reuses its file), each beginning with a ``run`` entry: ``--runs``
lists them (id, start in UTC, length, entries, ids, robot, board), ``--run ID`` (an id or a
unique prefix of one) shows only that run's entries. The file is only read, and may be read
while the daemon writes it.
"""

from __future__ import annotations

import argparse
import json
from datetime import UTC, datetime
from typing import TYPE_CHECKING

if TYPE_CHECKING:
    from host.journal.runs import Run
    from host.journal.store import JournalReader

NAME = "journal"
HELP = "show the last entries of a journal file, or of one daemon run in it"


def add_run_arguments(parser: argparse.ArgumentParser, default: str) -> None:
    """``--run ID`` and ``--runs``, as ``dxboard journal`` and ``dxboard report`` take them."""
    parser.add_argument("--run", metavar="ID",
                        help=f"one daemon run: its id or a unique prefix (default: {default})")
    parser.add_argument("--runs", action="store_true",
                        help="list the daemon runs the journal holds, oldest first, and stop")


def chosen_run(reader: JournalReader, args: argparse.Namespace) -> Run | None:
    """The run ``--run`` names (None without ``--run``); with ``--runs``, print every run."""
    from host.journal.runs import list_runs, pick

    runs = list_runs(reader)
    if args.runs:
        for r in runs:
            print(r.line())
        if not runs:
            print("no runs: the journal is empty")
        return None
    return None if args.run is None else pick(runs, args.run, str(reader.path))


def add_arguments(parser: argparse.ArgumentParser) -> None:
    from host.events import Kind

    parser.add_argument("file", metavar="FILE", help="journal file (SQLite)")
    parser.add_argument("--tail", type=int, default=20, metavar="N",
                        help="how many of the last entries to show (default: 20)")
    parser.add_argument("--kind", action="append", choices=[k.value for k in Kind],
                        metavar="K", help="only entries of this kind (may be repeated)")
    add_run_arguments(parser, "every run")
    parser.add_argument("--json", action="store_true", help="one JSON object a line")


def run(args: argparse.Namespace) -> int:
    from host.errors import UserError
    from host.journal.store import JournalReader
    from host.journal.summary import summarize

    if args.tail < 0:
        raise UserError(f"--tail {args.tail} is negative", "give --tail 0 or more")
    with JournalReader(args.file) as reader:
        one = chosen_run(reader, args)
        if args.runs:
            return 0
        entries = reader.tail(args.tail, kind=args.kind,
                              after_id=0 if one is None else one.after_id,
                              to_id=None if one is None else one.last_id)
    for entry in entries:
        if args.json:
            print(json.dumps(entry.to_json(), separators=(",", ":")))
        else:
            when = datetime.fromtimestamp(entry.wall, UTC).strftime("%Y-%m-%d %H:%M:%S.%f")[:-3]
            print(f"{entry.id:>8}  {when}  {entry.kind.value:<11}  {summarize(entry.payload)}")
    return 0
