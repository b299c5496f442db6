"""Class names defined more than once in dxboard's product code: one concept, one name.

``python scripts/names.py`` parses every module of ``protocol/``, ``firmware/``, ``emulator/`` and
``host/`` with :mod:`ast` and lists each class name that two or more modules define (top-level
and nested classes alike), with the places, most-defined first, then the count. ARCHITECTURE.md
asks for one class name per concept and, where two layers need different values, names that say
the layer (``BoardObservation``, ``MissionObservation``); the issue allows at most ``LIMIT``
names defined twice, each with a comment on why; ``KNOWN`` is the allow-list of those the
code has now, with the why; a doubled name outside it gets a line saying so. The script
reports and does not fail by default; ``--check`` (run by ``make lint``) exits 1 when more
than ``LIMIT`` names are defined twice or one outside ``KNOWN`` is (rename it, or add it to
``KNOWN`` with a comment at each place saying why). ``--root DIR`` reads another tree; a file
that does not parse is one line and exit code 2.
"""

from __future__ import annotations

import argparse
import ast
import sys
from collections.abc import Sequence
from pathlib import Path

ROOTS = ("protocol", "firmware", "emulator", "host")
LIMIT = 5  # the cap (issue 26, item 2)
# The names defined twice on purpose, and why (a comment at each place says it too). The
# page's Status and StatusFold and /diagnostics' are gone: one EventFold (host/fold) that both
# project, and /diagnostics' value is a DiagnosticStatus (issue 26, item 3).
KNOWN: dict[str, str] = {
    "BoardEvent": "the board client's value, and the same on the daemon's event stream (a "
                  "layer above, which the board may not import)",
    "Observation": "the diagnoser's value, and the same on the daemon's event stream (a "
                   "layer above)",
    "Task": "asyncio's, which the emulator's scheduler stands in for, and a planning task",
}


def definitions(root: Path) -> dict[str, list[str]]:
    """Class name -> the places (``path:line``) that define it, over the product code."""
    found: dict[str, list[str]] = {}
    for top in ROOTS:
        for path in sorted((root / top).rglob("*.py")):
            try:
                tree = ast.parse(path.read_text(encoding="utf-8"), filename=str(path))
            except SyntaxError as exc:
                raise ValueError(
                    f"{path}:{exc.lineno}: does not parse ({exc.msg}); fix the file"
                ) from exc
            for node in ast.walk(tree):
                if isinstance(node, ast.ClassDef):
                    place = f"{path.relative_to(root)}:{node.lineno}"
                    found.setdefault(node.name, []).append(place)
    return found


def twice(found: dict[str, list[str]]) -> list[tuple[str, list[str]]]:
    """The names defined in two or more modules, most-defined first."""
    out = []
    for name, places in found.items():
        modules = {p.rsplit(":", 1)[0] for p in places}
        if len(modules) > 1:
            out.append((name, places))
    return sorted(out, key=lambda item: (-len(item[1]), item[0]))


def main(argv: Sequence[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0] if __doc__ else None)
    parser.add_argument("--root", type=Path, default=Path(__file__).resolve().parent.parent,
                        help="the repository to read (default: this one)")
    parser.add_argument("--check", action="store_true",
                        help=f"exit 1 when more than {LIMIT} class names, or one not in "
                             "KNOWN, are defined twice")
    args = parser.parse_args(argv)
    try:
        doubles = twice(definitions(args.root))
    except ValueError as exc:
        print(f"names: {exc}", file=sys.stderr)
        return 2
    new = [name for name, _ in doubles if name not in KNOWN]
    for name, places in doubles:
        print(f"{name} x{len(places)}: {', '.join(places)}")
    for name in new:
        print(f"{name} is not in KNOWN: rename one, or add it to KNOWN in scripts/names.py "
              "with a comment at each place saying why")
    print(f"{len(doubles)} class names defined more than once (at most {LIMIT} wanted)")
    return 1 if args.check and (len(doubles) > LIMIT or new) else 0


if __name__ == "__main__":
    sys.exit(main())
