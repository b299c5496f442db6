"""The package graph of dxboard, read from the code's imports, checked against the layer order.

``python scripts/layers.py`` parses every module of ``protocol/``, ``firmware/``, ``emulator/``
and ``host/`` with :mod:`ast` (no third-party tool, nothing imported or run), folds each import
of ours into an arrow between two *packages* (``protocol``, ``firmware``, ``emulator`` as a
whole; inside ``host`` each subpackage or top-level module, ``host.repair``, ``host.events``),
prints the graph floor by floor, and exits 1 naming every arrow that runs *up* (a package
importing one on its own or a higher floor of ``LAYERS`` below) and every package cycle (a strongly
connected component of more than one package), 2 on bad input (a package missing from
``LAYERS``, a file that does not parse). Every import counts, wherever it stands: at the top,
inside a function (a lazy import is still a dependency) and under ``if TYPE_CHECKING:``. A
type-only import is not a run-time dependency, but a reader and mypy need the other package to
understand the signature, so it binds the layers just the same; such arrows are marked
``(type)`` so that the fix is obvious (usually a ``Protocol`` on the lower floor). Packages
on one floor know nothing of each other: an arrow between them is reported as sideways.
The benchmarks stand beside the product, not on the tests: a module of ``benchmarks/`` that
imports ``tests`` (anywhere in it, lazily too) fails the check as well, naming the place; what
a benchmark needs to launch comes from ``host.launch``, the rest from ``benchmarks/_rigs``.
``--root DIR`` checks another tree (the tests use a small fake one); ``--dot`` prints the graph
for Graphviz.
"""

from __future__ import annotations

import argparse
import ast
import sys
from collections.abc import Iterable, Iterator, Sequence
from dataclasses import dataclass
from pathlib import Path

# The floors, bottom first; a package imports only packages on lower floors (two on one floor
# know nothing of each other). Written from ARCHITECTURE.md ("Layers and what each may touch",
# "How data flows", "Where each concept lives") and MISSIONS.md, checked against the code.
LAYERS: tuple[tuple[str, ...], ...] = (
    ("protocol",),  # bytes in, events out; imports nothing of ours
    ("firmware",),
    ("emulator",),  # the firmware on a simulated HAL
    # shared by every floor
    ("host", "host.errors", "host.atoms", "host.layers", "host.lifeline", "host.cachefile"),
    ("host.events",),  # the one event stream's values
    ("host.fold",),  # the one fold of that stream, which every view reads
    ("host.transports",),  # bytes
    ("host.board",),  # messages
    ("host.diagnosis",),  # clauses and literals
    ("host.observers",),  # readings -> literals (diagnosis's Observation values)
    ("host.planning",),  # PDDL for everyone
    ("host.repair",),  # diagnosis -> repair plan -> actions
    ("host.journal",),
    ("host.skills",),  # layer 1 (MISSIONS.md)
    ("host.executive",),  # layer 2
    ("host.mission", "host.plandiag"),  # layer 3 and plan-execution diagnosis, side by side
    ("host.operator",),  # the operator socket
    ("host.ros", "host.web", "host.report", "host.deploy"),  # views of the stream, outputs
    ("host.learn",),  # the model learned from a running robot (reads host.ros's bags)
    ("host.fleet",),  # the Prometheus metrics (read the page's status) and the fleet view
    ("host.daemon",),  # wires layer 0 and its outputs
    ("host.launch",),  # starts robot and daemon; wires the mission layers to the daemon
    ("host.experiment",),
    ("host.commands",),  # composition: one module per command
    ("host.cli",),
    ("host.warm",),  # runs the command line's everyday commands in a warm process
    ("host.entry",),  # the console script: the warm server, else the command line
)

ROOTS = ("protocol", "firmware", "emulator", "host")


class BadInput(Exception):
    """The tree or the layer order cannot be checked; the message names the place and the fix."""


@dataclass(frozen=True, order=True)
class Arrow:
    """One import of ``target`` by ``source`` (packages), first seen at ``where``."""

    source: str
    target: str
    where: str
    type_only: bool


def package_of(module: str) -> str | None:
    """The graph node of a dotted module name of ours, None for anything else."""
    parts = module.split(".")
    if parts[0] not in ROOTS:
        return None
    if parts[0] != "host" or len(parts) == 1:
        return parts[0]
    return ".".join(parts[:2])


def _module_name(root: Path, path: Path) -> tuple[str, bool]:
    rel = path.relative_to(root).with_suffix("")
    parts = list(rel.parts)
    is_package = parts[-1] == "__init__"
    if is_package:
        parts = parts[:-1]
    return ".".join(parts), is_package


def _is_type_checking(test: ast.expr) -> bool:
    return (isinstance(test, ast.Name) and test.id == "TYPE_CHECKING") or (
        isinstance(test, ast.Attribute) and test.attr == "TYPE_CHECKING"
    )


def _imports(tree: ast.AST, module: str, is_package: bool) -> Iterator[tuple[str, int, bool]]:
    """(imported module, line, type-only) for every import statement in ``tree``."""
    type_only_lines: set[int] = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.If) and _is_type_checking(node.test):
            for inner in node.body:
                for sub in ast.walk(inner):
                    if isinstance(sub, ast.Import | ast.ImportFrom):
                        type_only_lines.add(sub.lineno)
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            for alias in node.names:
                yield alias.name, node.lineno, node.lineno in type_only_lines
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                base = module.split(".")
                if not is_package:
                    base = base[:-1]
                base = base[: len(base) - (node.level - 1)]
                target = ".".join([*base, node.module] if node.module else base)
            else:
                target = node.module or ""
            names = [f"{target}.{a.name}" for a in node.names] if target in ROOTS else [target]
            for name in names:
                yield name, node.lineno, node.lineno in type_only_lines


def scan(root: Path) -> list[Arrow]:
    """Every arrow between two different packages of the tree at ``root``."""
    arrows: dict[tuple[str, str, bool], Arrow] = {}
    for top in ROOTS:
        for path in sorted((root / top).rglob("*.py")):
            module, is_package = _module_name(root, path)
            source = package_of(module)
            if source is None:
                continue
            try:
                tree = ast.parse(path.read_text(encoding="utf-8"), filename=str(path))
            except SyntaxError as exc:
                raise BadInput(
                    f"{path}:{exc.lineno}: does not parse ({exc.msg}); fix the file"
                ) from exc
            for imported, line, type_only in _imports(tree, module, is_package):
                target = package_of(imported)
                if target is None or target == source:
                    continue
                key = (source, target, type_only)
                where = f"{path.relative_to(root)}:{line}"
                if key not in arrows or where < arrows[key].where:
                    arrows[key] = Arrow(source, target, where, type_only)
    return sorted(arrows.values())


def benchmarks_on_tests(root: Path) -> list[str]:
    """Every import of ``tests`` by a module of ``benchmarks/``, as a line naming the place."""
    found: list[str] = []
    for path in sorted((root / "benchmarks").rglob("*.py")):
        module, is_package = _module_name(root, path)
        try:
            tree = ast.parse(path.read_text(encoding="utf-8"), filename=str(path))
        except SyntaxError as exc:
            raise BadInput(
                f"{path}:{exc.lineno}: does not parse ({exc.msg}); fix the file") from exc
        for imported, line, _ in _imports(tree, module, is_package):
            if imported == "tests" or imported.startswith("tests."):
                found.append(f"benchmark imports tests: {path.relative_to(root)}:{line} imports "
                             f"{imported}; take it from host.launch or benchmarks/_rigs")
    return found


def floors(layers: Sequence[Sequence[str]]) -> dict[str, int]:
    """Package -> its floor number (0 at the bottom)."""
    return {name: number for number, floor in enumerate(layers) for name in floor}


def arrows_up(arrows: Iterable[Arrow], floor: dict[str, int]) -> list[Arrow]:
    """The arrows from a package to one on a higher floor or on its own (sideways)."""
    return [a for a in arrows if floor[a.target] >= floor[a.source]]


def cycles(arrows: Iterable[Arrow]) -> list[list[str]]:
    """The package cycles: strongly connected components of two or more (Tarjan)."""
    graph: dict[str, set[str]] = {}
    for a in arrows:
        graph.setdefault(a.source, set()).add(a.target)
        graph.setdefault(a.target, set())
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on_stack: set[str] = set()
    found: list[list[str]] = []

    def visit(node: str) -> None:
        index[node] = low[node] = len(index)
        stack.append(node)
        on_stack.add(node)
        for nxt in sorted(graph[node]):
            if nxt not in index:
                visit(nxt)
                low[node] = min(low[node], low[nxt])
            elif nxt in on_stack:
                low[node] = min(low[node], index[nxt])
        if low[node] == index[node]:
            component = []
            while True:
                top = stack.pop()
                on_stack.discard(top)
                component.append(top)
                if top == node:
                    break
            if len(component) > 1:
                found.append(sorted(component))

    for node in sorted(graph):
        if node not in index:
            visit(node)
    return sorted(found)


def _check_known(arrows: Iterable[Arrow], floor: dict[str, int]) -> None:
    for a in arrows:
        for name in (a.source, a.target):
            if name not in floor:
                raise BadInput(
                    f"{a.where}: package {name} has no floor; add it to LAYERS in scripts/layers.py"
                )


def report(arrows: list[Arrow], layers: Sequence[Sequence[str]]) -> tuple[list[str], int]:
    """The printed graph and the number of problems (arrows up + cycles)."""
    floor = floors(layers)
    _check_known(arrows, floor)
    lines = ["package graph, bottom floor first (-> imports; (type) = under TYPE_CHECKING only)"]
    for number, names in enumerate(layers):
        for name in names:
            targets = sorted({(a.target, a.type_only) for a in arrows if a.source == name})
            shown = ", ".join(t + (" (type)" if type_only else "") for t, type_only in targets)
            lines.append(f"  {number:2d} {name}" + (f" -> {shown}" if shown else ""))
    up = arrows_up(arrows, floor)
    loops = cycles(arrows)
    for a in up:
        kind = "sideways" if floor[a.target] == floor[a.source] else "up"
        kind += " (type only)" if a.type_only else ""
        lines.append(
            f"arrow {kind}: {a.source} (floor {floor[a.source]}) imports {a.target} "
            f"(floor {floor[a.target]}) at {a.where}"
        )
    for loop in loops:
        lines.append("cycle: " + " <-> ".join(loop))
    lines.append(f"{len(arrows)} arrows, {len(up)} running up or sideways, {len(loops)} cycles")
    return lines, len(up) + len(loops)


def dot(arrows: list[Arrow]) -> list[str]:
    """The graph in Graphviz's language."""
    body = [f'  "{a.source}" -> "{a.target}"' + (" [style=dashed]" if a.type_only else "")
            for a in arrows]
    return ["digraph dxboard {", *body, "}"]


def main(argv: Sequence[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0] if __doc__ else None)
    parser.add_argument("--root", type=Path, default=Path(__file__).resolve().parent.parent,
                        help="the repository to check (default: this one)")
    parser.add_argument("--dot", action="store_true", help="print the graph for Graphviz instead")
    args = parser.parse_args(argv)
    root: Path = args.root
    try:
        if not any((root / top).is_dir() for top in ROOTS):
            raise BadInput(
                f"{root}: none of {', '.join(ROOTS)} is here; pass the repository with --root"
            )
        arrows = scan(root)
        if args.dot:
            print("\n".join(dot(arrows)))
            return 0
        lines, problems = report(arrows, LAYERS)
        on_tests = benchmarks_on_tests(root)
    except BadInput as exc:
        print(f"layers: {exc}", file=sys.stderr)
        return 2
    lines += [*on_tests, f"{len(on_tests)} imports of tests/ by benchmarks/"]
    print("\n".join(lines))
    return 1 if problems or on_tests else 0


if __name__ == "__main__":
    sys.exit(main())
