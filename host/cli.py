"""The ``dxboard`` command line: one sub-command per module, loaded when it is used.

Each entry of ``COMMANDS`` names a module with ``NAME`` (its sub-command), ``HELP`` (one line),
``add_arguments(parser)`` and ``run(args) -> int``. Modules import their heavy dependencies
inside ``run`` so that ``dxboard --help`` stays fast. A ``DxboardError`` (a ``UserError`` or a
``RemoteError``) becomes one line on stderr and exit code 2; ``--verbose`` adds the traceback.
"""

from __future__ import annotations

import argparse
import importlib
import logging
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
    "inject": "host.commands.inject",
    "quarantine": "host.commands.quarantine",
    "hold": "host.commands.hold",
    "journal": "host.commands.journal",
    "report": "host.commands.report",
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
    except DxboardError as exc:  # a person's mistake or a failing peer: one line
        if args.verbose:
            traceback.print_exc()
        print(f"dxboard {args.command}: error: {exc}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        return 130
    return code


if __name__ == "__main__":
    sys.exit(main())
