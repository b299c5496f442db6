"""The ``dxboard`` command line: one sub-command per module, loaded when it is used.

Each entry of ``COMMANDS`` names a module with ``NAME`` (its sub-command), ``HELP`` (one line),
``add_arguments(parser)`` and ``run(args) -> int``. Only the module of the command that runs is
imported (``dxboard diagnose`` never loads the daemon's, the web page's or the ROS commands'
modules); ``dxboard --help``, an unknown command, or anything but ``-v`` before the command
loads them all, so the listing names every command. Modules import their heavy dependencies
inside ``run`` so that ``--help`` stays fast. A command whose module cannot be imported (a
dependency missing) is listed as unavailable and, when run, says why in one line, exit code 2.
A ``DxboardError`` (a ``UserError`` or a ``RemoteError``) becomes one line on stderr and exit
code 2; ``--verbose`` adds the traceback. A reader that closes our stdout early (``dxboard
journal --json | head``) ends any command quietly with exit code 141 (128 + SIGPIPE, what a
shell shows for a process a closed pipe stopped), here once for every command.
"""

from __future__ import annotations

import argparse
import contextlib
import functools
import importlib
import logging
import os
import select
import signal
import sys
import traceback
from collections.abc import Sequence
from types import ModuleType

from host.errors import DxboardError, UserError

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
    "fleet": "host.commands.fleet",
    "warm": "host.warm.command",  # above the command line: it forks the commands it runs
}


def _load(module_name: str) -> ModuleType:
    return importlib.import_module(module_name)


def chosen_command(argv: Sequence[str]) -> str | None:
    """The sub-command ``argv`` runs when only ``-v``/``--verbose`` stand before it: the one
    module to load. None (load every command) for ``--help``, an unknown command or any other
    option first, so that argparse sees what it always saw."""
    for token in argv:
        if token not in ("-v", "--verbose"):
            return token if token in COMMANDS else None
    return None


def build_parser(only: str | None = None) -> argparse.ArgumentParser:
    """The parser of every command, or of the command ``only`` alone (its module the only one
    imported)."""
    parser = argparse.ArgumentParser(
        prog="dxboard",
        description="dxboard: a self-diagnosing, self-repairing power system for robots.",
        formatter_class=_formatter(argparse.HelpFormatter),
    )
    parser.add_argument(
        "-v", "--verbose", action="store_true", help="log more and show tracebacks on errors"
    )
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    sub.required = True
    for name, module_name in COMMANDS.items():
        if only is None or name == only:
            _add_command(sub, name, module_name, strict=only is not None)
    return parser


def _add_command(sub: argparse._SubParsersAction[argparse.ArgumentParser], name: str,
                 module_name: str, strict: bool) -> None:
    """Add ``name``'s parser. A module that cannot be imported raises ``UserError`` when
    ``strict`` (the command about to run), else is listed as unavailable."""
    try:
        module = _load(module_name)
    except ImportError as exc:  # a dependency missing
        if strict:
            raise _unavailable(module_name, exc) from exc
        command = sub.add_parser(name, help=f"(unavailable: {exc})", add_help=False)
        command.add_argument("_rest", nargs=argparse.REMAINDER, help=argparse.SUPPRESS)
        command.set_defaults(_run=_Unavailable(module_name, exc))
        return
    command = sub.add_parser(
        name,
        help=module.HELP,
        description=module.__doc__,
        formatter_class=_formatter(argparse.RawDescriptionHelpFormatter),
    )
    module.add_arguments(command)
    command.set_defaults(_run=module.run)


def _formatter(kind: type[argparse.HelpFormatter]) -> argparse._FormatterClass:
    """``kind`` for the terminal's width, read once here: argparse's own formatter imports
    ``shutil`` and asks the terminal again for every argument added (a few ms a command)."""
    width = _columns() - 2
    return functools.partial(kind, width=width)


def _columns() -> int:
    """The terminal's width as ``shutil.get_terminal_size`` finds it: ``$COLUMNS``, else
    stdout's terminal, else 80."""
    with contextlib.suppress(ValueError):
        columns = int(os.environ.get("COLUMNS", "0"))
        if columns > 0:
            return columns
    try:
        columns = os.get_terminal_size(sys.__stdout__.fileno()).columns  # type: ignore[union-attr]
    except (AttributeError, ValueError, OSError):
        columns = 0
    return columns if columns > 0 else 80


class _Unavailable:
    """The ``run`` of a command whose module could not be imported: one clear line."""

    def __init__(self, module_name: str, exc: ImportError) -> None:
        self.module_name = module_name
        self.exc = exc

    def __call__(self, args: argparse.Namespace) -> int:
        raise _unavailable(self.module_name, self.exc) from self.exc


def _unavailable(module_name: str, exc: ImportError) -> UserError:
    return UserError(f"cannot load {module_name}: {exc}",
                     "install dxboard with its dependencies: make .venv/.installed")


def main(argv: Sequence[str] | None = None) -> int:
    if argv is None:
        argv = sys.argv[1:]
    only = chosen_command(argv)
    try:
        parser = build_parser(only)
    except UserError as exc:  # the command's module cannot be imported: one line
        if "-v" in argv or "--verbose" in argv:
            traceback.print_exc()
        print(f"dxboard {only}: error: {exc}", file=sys.stderr)
        return 2
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
