"""YAML with line numbers, so that model errors can name the line a person must fix.

``load(text)`` parses one YAML document with PyYAML's safe composer and returns the plain
Python value together with ``Lines``: a map from a path of keys and indexes (``("components",
"jaguar", "channel")``) to the 1-based line where that value starts. A missing path falls back
to its nearest recorded ancestor. Syntax errors become ``ValueError`` carrying the line.
"""

from __future__ import annotations

from typing import Any

import yaml

Path = tuple[object, ...]


class Lines:
    """Line numbers of the values of a YAML document, by path."""

    def __init__(self) -> None:
        self._lines: dict[Path, int] = {}

    def record(self, path: Path, line: int) -> None:
        self._lines.setdefault(path, line)

    def __call__(self, *path: object) -> int:
        p: Path = tuple(path)
        while p and p not in self._lines:
            p = p[:-1]
        return self._lines.get(p, 1)


class YamlSyntaxError(ValueError):
    def __init__(self, message: str, line: int) -> None:
        super().__init__(message)
        self.line = line


def load(text: str) -> tuple[Any, Lines]:
    """Parse ``text``; return ``(value, lines)``. Raises ``YamlSyntaxError``."""
    try:
        node = yaml.compose(text, Loader=yaml.SafeLoader)
    except yaml.MarkedYAMLError as exc:
        mark = exc.problem_mark or exc.context_mark
        line = mark.line + 1 if mark is not None else 1
        raise YamlSyntaxError(f"YAML syntax error: {exc.problem or exc}", line) from exc
    lines = Lines()
    if node is None:
        return None, lines
    return _convert(node, (), lines), lines


def _convert(node: yaml.Node, path: Path, lines: Lines) -> Any:
    lines.record(path, node.start_mark.line + 1)
    if isinstance(node, yaml.MappingNode):
        out: dict[Any, Any] = {}
        for key_node, value_node in node.value:
            key = _scalar(key_node)
            lines.record((*path, key), key_node.start_mark.line + 1)
            out[key] = _convert(value_node, (*path, key), lines)
        return out
    if isinstance(node, yaml.SequenceNode):
        return [_convert(item, (*path, i), lines) for i, item in enumerate(node.value)]
    return _scalar(node)


def _scalar(node: yaml.Node) -> Any:
    if isinstance(node, yaml.ScalarNode):
        loader = yaml.SafeLoader("")
        return loader.construct_object(node, deep=True)
    return str(node.start_mark)
