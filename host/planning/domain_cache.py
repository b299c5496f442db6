"""A cache of parsed repair domains, as Python's ``.pyc`` is of modules.

The ``pddl`` library builds its grammar (lark, LALR tables) each time a parser is made: about
0.3 s of CPU in every ``dxboard plan``, ``model check`` or ``explain``, for a domain of a few
kilobytes that converts into a few hundred small immutable values. ``stored(text, path,
parse)`` returns the ``Domain`` of domain text from the user's cache directory
(``$XDG_CACHE_HOME/dxboard/domains``, else ``~/.cache/dxboard/domains``) when an entry for it is
there and still true, else ``parse()``'s, stored for the next run. One entry per path (named
by its name and a checksum of it); an entry holds its key first: the stored form's
``VERSION``, the interpreter's cache tag, the path, the text's length, the size and
``st_mtime_ns`` of the converter's own sources (so a changed dxboard never reads an old entry)
and of the ``pddl`` library's; then the text itself, compared in full, and the domain. A stale,
damaged or foreign entry is rebuilt and overwritten; an unwritable cache directory only means
nothing is stored (logged at debug level). Entries are written to a temporary file and renamed
into place, so a reader never sees half of one. The entry is a pickle: trusted as far as the
user's own cache directory is (whoever can write there can already change the user's files).
"""

from __future__ import annotations

import importlib.util
import logging
import os
import sys
import zlib
from collections.abc import Callable
from pathlib import Path
from typing import TYPE_CHECKING

from host.cachefile import cache_root, read_entry, write_entry

if TYPE_CHECKING:
    from host.planning.domain import Domain

log = logging.getLogger(__name__)

#: the stored form; bump when what an entry holds changes
VERSION = 1
#: the modules that make a ``Domain`` from the parsed file (beside this one)
CONVERTER_FILES = ("domain.py", "vocabulary.py", "errors.py", "domain_cache.py")
_HERE = Path(__file__).resolve().parent


def cache_dir() -> Path:
    """Where entries live: ``$XDG_CACHE_HOME/dxboard/domains`` (``~/.cache`` by default)."""
    return cache_root() / "domains"


def _stamp(path: str | Path) -> tuple[str, int, int]:
    """A source file's real path (one environment reached through two links is one), size and
    ``st_mtime_ns``."""
    real = os.path.realpath(path)
    try:
        st = os.stat(real)
    except OSError:
        return (real, -1, -1)
    return (real, st.st_size, st.st_mtime_ns)


def _key(text: str, path: Path) -> tuple[object, ...]:
    spec = importlib.util.find_spec("pddl")
    library = _stamp(spec.origin) if spec is not None and spec.origin else ("pddl", -1, -1)
    return (VERSION, sys.implementation.cache_tag, str(path), len(text),
            tuple(_stamp(_HERE / name) for name in CONVERTER_FILES), library)


def entry_path(path: Path) -> Path:
    """The entry of the domain read from ``path``: its name and a checksum of its absolute
    form (two paths with one checksum overwrite each other's entry, never mix: the key holds
    the path)."""
    where = os.path.abspath(path)
    return cache_dir() / f"{path.name}-{zlib.crc32(where.encode()):08x}.pickle"


def stored(text: str, path: Path, parse: Callable[[], Domain]) -> Domain:
    """The domain of ``text`` (read from ``path``): from its entry when that holds the same
    text, else ``parse()``'s, stored. Errors of ``parse`` pass through (nothing is stored)."""
    from host.planning.domain import Domain

    key = _key(text, path)
    entry = entry_path(path)
    stored = read_entry(entry, key)
    if isinstance(stored, tuple) and len(stored) == 2:
        old, domain = stored
        if old == text and isinstance(domain, Domain):
            return domain
    if stored is not None:
        log.debug("%s: domain cache entry %s is stale", path, entry)
    domain = parse()
    write_entry(entry, key, (text, domain))
    return domain
