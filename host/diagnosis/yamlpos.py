"""YAML with line numbers, so that model errors can name the line a person must fix.

``load(text)`` parses one YAML document and returns the plain Python value together with
``SourceLines``: a map from a path of keys and indexes (``("components", "jaguar",
"channel")``) to the 1-based line where that value starts. A missing path falls back to its
nearest recorded ancestor. The line table is built only when a line is first asked for (an
error, or a loader that records lines), from a second, node-only pass over the text: a valid
file read by a loader that asks for no line is parsed once. ``typed=False`` (every scalar a
string, the tug format's reading) builds the value straight from libyaml's events. Syntax
errors become ``YamlSyntaxError`` carrying the line. The parsing itself is
``host.diagnosis.yamlparse``, PyYAML's side, imported only when a document is really parsed.

``load(text, source=FILE)`` keeps the parsed value of a file in the user's cache directory, as
Python's ``.pyc`` is of a module (``$XDG_CACHE_HOME/dxboard/yaml``, one entry a file, named by a
checksum of its absolute path; ``host.cachefile``): the next ``load`` of the same text from the
same file unpickles the value instead of importing PyYAML and parsing. The entry's key holds
the stored form's ``VERSION``, the interpreter's cache tag, the path, ``typed``, the text's
length and the size and ``st_mtime_ns`` of this module's, ``yamlparse``'s and PyYAML's sources;
the entry holds the text itself too, compared in full, so a changed file, a changed reader or
another PyYAML never reads an old value; and the line table, which the model's loader asks for
(it records each component's line). A robot directory's ``system.yaml`` is read by several
loaders in one command (the model, its processes, its observers' source): each read is the
cache's, and every caller gets a value of its own (unpickled anew, so one caller's changes
never reach another's).

Every file a person gives is bounded before it is built (``yamlparse.check_bounds``): at most
``MAX_CHARS`` characters, and at most ``MAX_NODES`` values once aliases are expanded, nested at
most ``MAX_DEPTH`` deep. A "billion laughs" file (nine aliases of nine aliases of ...) is
refused from its events in milliseconds, with ``YamlTooBig`` (a ``YamlSyntaxError``, so every
caller names the file and the line) instead of growing to gigabytes in whatever walks it.
Ordinary aliases (a shared settings block) pass. Only a document that parsed is stored, so a
cached value was bounded when it was built. ``read_text`` reads a file with its size checked
first, for the loaders that read files themselves.
"""

from __future__ import annotations

import importlib.util
import os
import pathlib
import sys
import zlib
from typing import Any

from host.cachefile import cache_root, read_entry, write_entry
from host.errors import UserError

Path = tuple[object, ...]

MAX_CHARS = 8 * 1024 * 1024  # files.MAX_BYTES: far above the largest real model
MAX_NODES = 1_000_000  # values after alias expansion
MAX_DEPTH = 200  # nesting of sequences and mappings

#: the stored form of a cached document; bump when what an entry holds changes
VERSION = 1
_HERE = pathlib.Path(__file__).resolve().parent


class YamlSyntaxError(ValueError):
    def __init__(self, message: str, line: int, fix: str = "fix the YAML syntax") -> None:
        super().__init__(message)
        self.line = line
        self.fix = fix  # what the person should do


class YamlTooBig(YamlSyntaxError):
    """The document is larger than a person's file may be (see the module): a refusal."""

    def to_user_error(self, file: object) -> UserError:
        return UserError(f"{file}:{self.line}: {self}", self.fix)


def read_text(file: pathlib.Path, max_chars: int = MAX_CHARS) -> str:
    """``file``'s UTF-8 text, refused with ``YamlTooBig`` before reading when it is larger
    than ``max_chars`` bytes (OSError and UnicodeDecodeError pass to the caller)."""
    size = file.stat().st_size
    if size > max_chars:
        raise YamlTooBig(f"the file has {size:,} bytes, more than the {max_chars:,} a "
                         f"file here may have", 1, "give a smaller file")
    return file.read_text(encoding="utf-8")


class SourceLines:
    """Line numbers of the values of a YAML document, by path (computed on first use)."""

    def __init__(self, text: str = "", typed: bool = True,
                 table: dict[Path, int] | None = None) -> None:
        self._text = text
        self._typed = typed
        # None: built from the text when first asked for; no text: no line is known
        self._lines: dict[Path, int] | None = table if table is not None else (
            None if text else {})

    def __call__(self, *path: object) -> int:
        table = self._table()
        p: Path = tuple(path)
        while p and p not in table:
            p = p[:-1]
        return table.get(p, 1)

    def _table(self) -> dict[Path, int]:
        if self._lines is None:
            from host.diagnosis.yamlparse import line_table

            self._lines = line_table(self._text, self._typed)
        return self._lines


def load(text: str, typed: bool = True,
         source: pathlib.Path | None = None) -> tuple[Any, SourceLines]:
    """Parse ``text``; return ``(value, lines)``. ``typed=False`` reads every scalar as a
    string (no implicit ints, floats or booleans: half the time on a large file of
    strings). ``source``: the file ``text`` was read from, whose parsed value is kept in the
    cache (see the module). Raises ``YamlSyntaxError`` (``YamlTooBig`` beyond the bounds)."""
    if source is None:
        from host.diagnosis.yamlparse import parse

        return parse(text, typed), SourceLines(text, typed)
    key = _key(source, typed, text)
    entry = cache_root() / "yaml" / f"{source.name}-{zlib.crc32(str(key[2]).encode()):08x}.pickle"
    stored = read_entry(entry, key)
    if isinstance(stored, tuple) and len(stored) == 3 and stored[0] == text:
        return stored[1], SourceLines(text, typed, stored[2])
    from host.diagnosis.yamlparse import line_table, parse

    value = parse(text, typed)
    table = line_table(text, typed)  # stored too: loaders record the lines of what they build
    write_entry(entry, key, (text, value, table))
    return value, SourceLines(text, typed, table)


def _key(source: pathlib.Path, typed: bool, text: str) -> tuple[object, ...]:
    return (VERSION, sys.implementation.cache_tag, os.path.abspath(source), typed, len(text),
            _readers())


_READERS: tuple[tuple[int, int], ...] | None = None


def _readers() -> tuple[tuple[int, int], ...]:
    """The size and ``st_mtime_ns`` of this module's, ``yamlparse``'s and PyYAML's sources,
    found once a process (PyYAML's without importing it)."""
    global _READERS
    if _READERS is None:
        spec = importlib.util.find_spec("yaml")
        files = [_HERE / "yamlpos.py", _HERE / "yamlparse.py"]
        if spec is not None and spec.origin:
            files.append(pathlib.Path(spec.origin))
        _READERS = tuple(_stamp(p) for p in files)
    return _READERS


def _stamp(path: pathlib.Path) -> tuple[int, int]:
    try:
        st = os.stat(path)
    except OSError:
        return (-1, -1)
    return (st.st_size, st.st_mtime_ns)

