"""The ``dxboard`` command line: one sub-command per module, loaded when it is used.

Each entry of ``COMMANDS`` names a module with ``NAME`` (its sub-command), ``HELP`` (one line),
``add_arguments(parser)`` and ``run(args) -> int``. Modules import their heavy dependencies
inside ``run`` so that ``dxboard --help`` stays fast. A ``DxboardError`` (a ``UserError`` or a
``RemoteError``) becomes one line on stderr and exit code 2; ``--verbose`` adds the traceback.
A reader that closes our stdout early (``dxboard journal --json | head``) ends any command
quietly with exit code 141 (128 + SIGPIPE, what a shell shows for a process a closed pipe
stopped), here once for every command.
"""

from __future__ import annotations

import argparse
import contextlib
import importlib
import logging
import os
import select
import signal
import sys
import traceback
from collections.abc import Sequence
from types import ModuleType

from host.errors import DxboardError

# sub-command -> module implementing it (in the order --help lists them)
COMMANDS: dict[str, str] = {
    "run": "host.commands.run",
    "protocol": "host.commands.protocol",
    "model": "host.commands.model",
    "diagnose": "host.commands.diagnose",
    "plan": "host.commands.plan",
    "explain": "host.commands.explain",
    "inject": "host.commands.inject",
    "quarantine": "host.commands.quarantine",
    "hold": "host.commands.hold",
    "journal": "host.commands.journal",
    "report": "host.commands.report",
    "record": "host.commands.record",
    "replay": "host.commands.replay",
    "board": "host.commands.board",
    "flash": "host.commands.flash",
    "emulate": "host.commands.emulate",
    "experiment": "host.commands.experiment",
    "mission": "host.commands.mission",
}


def _load(module_name: str) -> ModuleType:
    return importlib.import_module(module_name)


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="dxboard",
        description="dxboard: a self-diagnosing, self-repairing power system for robots.",
    )
    parser.add_argument(
        "-v", "--verbose", action="store_true", help="log more and show tracebacks on errors"
    )
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    sub.required = True
    for name, module_name in COMMANDS.items():
        module = _load(module_name)
        command = sub.add_parser(
            name,
            help=module.HELP,
            description=module.__doc__,
            formatter_class=argparse.RawDescriptionHelpFormatter,
        )
        module.add_arguments(command)
        command.set_defaults(_run=module.run)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    logging.basicConfig(
        level=logging.DEBUG if args.verbose else logging.WARNING,
        format="%(asctime)s %(levelname)s %(name)s: %(message)s",
    )
    try:
        code: int = args._run(args)
        sys.stdout.flush()  # inside the try: a closed pipe shows here, not at exit
    except BrokenPipeError:
        if not _stdout_gone():  # a socket's, not ours: a bug to show
            raise
        return _quiet_stdout()
    except DxboardError as exc:  # a person's mistake or a failing peer: one line
        if args.verbose:
            traceback.print_exc()
        print(f"dxboard {args.command}: error: {exc}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        return 130
    return code


def _stdout_gone() -> bool:
    """True when nobody reads our stdout any more (its pipe or socket is closed)."""
    try:
        poller = select.poll()
        poller.register(sys.stdout.fileno(), select.POLLOUT)
        return any(ev & (select.POLLERR | select.POLLHUP) for _, ev in poller.poll(0))
    except (OSError, ValueError, AttributeError):  # not a file (an embedding, a test capture)
        return False


def _quiet_stdout() -> int:
    """Point stdout at /dev/null, so that what is still buffered cannot fail again when the
    interpreter flushes at exit; the exit code of a process stopped by a closed pipe."""
    with contextlib.suppress(OSError, ValueError):
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())
        os.close(devnull)
    return 128 + signal.SIGPIPE


if __name__ == "__main__":
    sys.exit(main())
