"""Entries of dxboard's cache in the user's cache directory, as Python's ``.pyc`` files are.

What a command would otherwise parse again on every run (a model file's encoding, a repair
domain, a YAML document) is kept under ``cache_root()`` (``$XDG_CACHE_HOME/dxboard``, else
``~/.cache/dxboard``), one file an entry. An entry is two pickles: its key first (small, read
and compared before anything else), then the value. ``read_entry(entry, key)`` returns the
value only when the stored key equals ``key``; a missing, stale, truncated or otherwise
damaged entry is ``None`` (the caller rebuilds it; logged at debug level). ``write_entry``
writes to a temporary file and renames it into place, so that a reader never sees half an
entry; an unwritable or full cache directory only means that nothing is stored. The cyclic
collector is paused while an entry is read (entries hold no cycles; a collection in the middle
of a large one cost as much as the read). Entries are pickles: trusted as far as the user's
own cache directory is (whoever can write there can already change the user's files).
"""

from __future__ import annotations

import contextlib
import gc
import logging
import os
import pickle
from pathlib import Path

log = logging.getLogger(__name__)


def cache_root() -> Path:
    """``$XDG_CACHE_HOME/dxboard`` (``~/.cache/dxboard`` when the variable is unset)."""
    base = os.environ.get("XDG_CACHE_HOME") or os.path.join(os.path.expanduser("~"), ".cache")
    return Path(base) / "dxboard"


def read_entry(entry: Path, key: object) -> object | None:
    """The value stored in ``entry`` under ``key``; None when there is none that is true."""
    collecting = gc.isenabled()
    gc.disable()
    try:
        with open(entry, "rb") as f:
            if pickle.load(f) != key:
                log.debug("cache entry %s is stale", entry)
                return None
            value: object = pickle.load(f)
            return value
    except FileNotFoundError:
        return None
    # a damaged entry can fail in any way unpickling can (UnpicklingError, EOFError,
    # ValueError, TypeError, AttributeError, ...): it is only a cache, so it is rebuilt
    except Exception as exc:
        log.debug("cache entry %s unreadable (%s): rebuilt", entry, exc)
        return None
    finally:
        if collecting:
            gc.enable()


def write_entry(entry: Path, key: object, value: object) -> None:
    """Store ``value`` under ``key`` in ``entry``, atomically; on an OSError store nothing."""
    tmp = entry.with_name(f"{entry.name}.{os.getpid()}.tmp")
    try:
        entry.parent.mkdir(parents=True, exist_ok=True)
        with open(tmp, "wb") as f:
            pickle.dump(key, f, protocol=pickle.HIGHEST_PROTOCOL)
            pickle.dump(value, f, protocol=pickle.HIGHEST_PROTOCOL)
        os.replace(tmp, entry)
    except OSError as exc:  # a read-only or full cache directory: work on, store nothing
        log.debug("cannot write cache entry %s: %s", entry, exc)
        with contextlib.suppress(OSError):
            tmp.unlink(missing_ok=True)
