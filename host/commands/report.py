"""Draw a journal's repair history: ``dxboard report JOURNAL -o FILE.png|FILE.svg [--run ID]``.

A timeline like paper 000's figures 5 and 6, of one daemon run (a journal holds every run that
wrote to it; the latest unless ``--run`` names another): one row per component (hardware first, then
drivers, then nodes), red while the component is in the first-ranked diagnosis, green while
it is not, grey before the first diagnosis, a thin amber band where a diagnosis was taken back
within the repair debounce (0.5 s) and nothing was repaired (a loaded machine's passing
verdict, not a fault); the repair actions along the top as bars from
start to end, failed and timed-out ones hatched and labelled; a dashed line where everything
became normal again ("all normal at 38.3 s"). Options:

  -o FILE            the image to write; .png or .svg picks the format
  --run ID           the daemon run to draw: its id or a unique prefix (default: the latest)
  --runs             list the runs the journal holds (id, start, length, entries) and stop
  --model DIR        the robot model (system.yaml): all its components as rows, in its order,
                     grouped by kind (hardware SH/H, drivers SN/HN, nodes N)
  --from X, --to X   a window: seconds on the run's time axis (12.5) or a journal id (#120);
                     the axis then counts from the window's start
  --title TEXT       replaces the title (robot: journal name)
  --dpi N            resolution of a PNG (default 150)

The journal is only read, and may be read while the daemon writes it.
"""

from __future__ import annotations

import argparse

NAME = "report"
HELP = "draw a journal as a timeline (PNG/SVG) like the paper's figures 5 and 6"


def add_arguments(parser: argparse.ArgumentParser) -> None:
    from host.commands.journal import add_run_arguments

    parser.add_argument("journal", metavar="JOURNAL", help="journal file (SQLite)")
    parser.add_argument("-o", "--output", metavar="FILE",
                        help="image to write: FILE.png or FILE.svg")
    add_run_arguments(parser, "the latest")
    parser.add_argument("--model", metavar="SYSTEM_DIR",
                        help="robot model: its components as rows, grouped by kind")
    parser.add_argument("--from", dest="start", metavar="X",
                        help="window start: seconds (12.5) or a journal id (#120)")
    parser.add_argument("--to", dest="end", metavar="X",
                        help="window end: seconds (40) or a journal id (#300)")
    parser.add_argument("--title", help="title of the chart (default: robot: journal name)")
    parser.add_argument("--dpi", type=int, default=150, help="PNG resolution (default: 150)")


def run(args: argparse.Namespace) -> int:
    from pathlib import Path

    from host.commands.journal import chosen_run
    from host.errors import UserError
    from host.journal.store import JournalReader
    from host.report.source import load_timeline, parse_bound

    if args.runs:
        with JournalReader(args.journal) as reader:
            chosen_run(reader, args)
        return 0
    if not args.output:
        raise UserError("which image? -o is missing",
                        "give -o FILE.png or -o FILE.svg (or --runs to list the runs)")
    out = Path(args.output)
    if out.suffix.lower() not in (".png", ".svg"):
        raise UserError(f"-o {args.output}: cannot write {out.suffix or 'a file without a suffix'}",
                        "end the file name in .png or .svg")
    if not out.parent.is_dir():
        raise UserError(f"-o {args.output}: directory {out.parent} does not exist",
                        "create it first, or write the image elsewhere")
    if not 20 <= args.dpi <= 1200:
        raise UserError(f"--dpi {args.dpi} is out of range", "give --dpi between 20 and 1200")
    start = parse_bound("--from", args.start)
    end = parse_bound("--to", args.end)
    timeline = load_timeline(args.journal, model=args.model, start=start, end=end,
                             run=args.run)

    from host.report.chart import render  # matplotlib only when there is something to draw

    try:
        render(timeline, out, title=args.title, dpi=args.dpi)
    except OSError as exc:
        raise UserError(f"-o {args.output}: cannot write ({exc.strerror or exc})",
                        "check the directory's permissions and free space") from exc
    run = f"run {timeline.run}: " if timeline.run else ""
    print(f"wrote {out} ({run}{len(timeline.rows)} components, {len(timeline.actions)} "
          f"actions, {timeline.end:.1f} s)")
    return 0
