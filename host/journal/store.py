"""The journal's SQLite file: schema, opening with clear errors, and the reader API.

One table, ``entries(id, kind, wall, mono, data)``, with ``data`` the payload's JSON, indexed
by ``(kind, id)`` and by ``wall``. The file is marked with ``PRAGMA application_id`` (so a
stranger's SQLite file is refused rather than written into) and ``PRAGMA user_version`` (the
schema version), and runs in WAL mode: readers (the web page, ``dxboard journal``, tests) never
block the writer, and a committed transaction survives the process being killed. ``connect``
turns every way a file can be wrong (missing directory, a directory, not SQLite, another
program's database, a newer schema, read-only) into a one-line ``UserError`` naming the file
and the fix. ``JournalReader`` answers the queries the daemon's readers need: the tail, entries
after an id (for live following), by kind, a wall-time range, an id range (one daemon run,
``host.journal.runs``), counts and size. It owns one
connection guarded by a lock, so it may be called from worker threads
(``asyncio.to_thread``).
"""

from __future__ import annotations

import contextlib
import json
import logging
import os
import sqlite3
import threading
from collections.abc import Iterable
from pathlib import Path
from typing import Any

from host.errors import UserError
from host.events import Kind, Note, payload_from_json
from host.journal.entries import Entry

log = logging.getLogger(__name__)

APPLICATION_ID = 0x44584A31  # "DXJ1"
SCHEMA_VERSION = 1

_SCHEMA = """
CREATE TABLE IF NOT EXISTS entries (
    id   INTEGER PRIMARY KEY AUTOINCREMENT,
    kind TEXT NOT NULL,
    wall REAL NOT NULL,
    mono REAL NOT NULL,
    data TEXT NOT NULL
);
CREATE INDEX IF NOT EXISTS entries_kind ON entries (kind, id);
CREATE INDEX IF NOT EXISTS entries_wall ON entries (wall);
"""

# the fixes differ for the daemon (which takes --journal FILE) and for the commands that only
# read a journal (dxboard journal, report: the file is their argument, they have no --journal)
_FIX_NEW = "give --journal a new file name, or move this file away"
_FIX_READ = "check the path: give the journal file a daemon wrote"


def _bad(path: Path, why: str, fix: str = _FIX_NEW) -> UserError:
    return UserError(f"journal {path}: {why}", fix)


def connect(path: str | os.PathLike[str], *, create: bool, sync: str = "full",
            busy_timeout_s: float = 10.0) -> sqlite3.Connection:
    """Open (and with ``create`` make) a journal file in WAL mode; ``UserError`` if unusable."""
    p = Path(path)
    if p.is_dir():
        raise _bad(p, "is a directory", "give --journal a file name inside it" if create
                   else "give the journal file inside it")
    if not p.exists():
        if not create:
            raise _bad(p, "no such file", _FIX_READ)
        if not p.parent.is_dir():
            raise _bad(p, f"directory {p.parent} does not exist", "create it first")
    elif not os.access(p, os.R_OK):
        raise _bad(p, "cannot be read (permission denied)", "fix its permissions")
    try:
        conn = sqlite3.connect(p, isolation_level=None, check_same_thread=False,
                               timeout=busy_timeout_s)
    except sqlite3.Error as exc:
        raise _bad(p, f"cannot be opened ({exc})", "check the path and its permissions") from exc
    try:
        _check_and_setup(conn, p, create=create, sync=sync)
    except BaseException:
        conn.close()
        raise
    return conn


def _check_and_setup(conn: sqlite3.Connection, p: Path, *, create: bool, sync: str) -> None:
    try:
        app_id = conn.execute("PRAGMA application_id").fetchone()[0]
        version = conn.execute("PRAGMA user_version").fetchone()[0]
        tables = conn.execute("SELECT count(*) FROM sqlite_master").fetchone()[0]
    except sqlite3.DatabaseError as exc:
        raise _bad(p, f"is not a dxboard journal ({exc})",
                   _FIX_NEW if create else _FIX_READ) from exc
    if app_id != APPLICATION_ID:
        if not tables and not create:
            raise _bad(p, "is empty, not a dxboard journal", _FIX_READ)
        if tables:
            raise _bad(p, "is an SQLite file of another program, not a dxboard journal",
                       _FIX_NEW if create else _FIX_READ)
    elif version > SCHEMA_VERSION:
        raise _bad(p, f"has schema version {version}, newer than this dxboard's "
                   f"{SCHEMA_VERSION}", "upgrade dxboard, or give --journal a new file"
                   if create else "upgrade dxboard to read it")
    try:
        # only the writer switches the file to WAL; a reader takes it as it is (and so can
        # read a journal it may not write)
        mode = conn.execute("PRAGMA journal_mode=WAL" if create else "PRAGMA journal_mode"
                            ).fetchone()[0]
        if create and str(mode).lower() != "wal":
            raise _bad(p, f"cannot use WAL mode (got {mode})", "put the journal on a local disk")
        if create:
            conn.execute(f"PRAGMA synchronous={'FULL' if sync == 'full' else 'NORMAL'}")
            conn.execute("PRAGMA journal_size_limit=4194304")
        if create and app_id != APPLICATION_ID:
            conn.executescript(_SCHEMA)
            conn.execute(f"PRAGMA application_id={APPLICATION_ID}")
            conn.execute(f"PRAGMA user_version={SCHEMA_VERSION}")
    except sqlite3.OperationalError as exc:
        raise _bad(p, f"cannot be written ({exc})",
                   "check the disk and the file's permissions") from exc
    except sqlite3.DatabaseError as exc:
        raise _bad(p, f"is damaged ({exc})") from exc


def row_to_entry(row: tuple[Any, ...]) -> Entry:
    """Decode one ``(id, kind, wall, mono, data)`` row; a bad payload becomes an error note."""
    ident, kind, wall, mono, data = row
    try:
        payload = payload_from_json(kind, json.loads(data))
    except (ValueError, TypeError) as exc:
        log.warning("journal entry %d (%s) cannot be decoded: %s", ident, kind, exc)
        payload = Note(f"undecodable {kind} entry: {data[:200]}", "error")
    return Entry(int(ident), float(wall), float(mono), payload)


def _kinds(kind: Kind | str | Iterable[Kind | str] | None) -> list[str] | None:
    if kind is None:
        return None
    if isinstance(kind, str):
        return [Kind(kind).value]
    return [Kind(k).value for k in kind]


class JournalReader:
    """Read-side queries; every list comes oldest first (ascending id)."""

    _COLUMNS = "SELECT id, kind, wall, mono, data FROM entries"

    def __init__(self, path: str | os.PathLike[str], conn: sqlite3.Connection | None = None):
        self.path = Path(path)
        self._conn = conn if conn is not None else connect(path, create=False)
        self._lock = threading.Lock()

    def close(self) -> None:
        with self._lock:
            self._conn.close()

    def __enter__(self) -> JournalReader:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def _select(self, where: list[str], params: list[Any], order: str,
                limit: int | None) -> list[Entry]:
        sql = self._COLUMNS
        if where:
            sql += " WHERE " + " AND ".join(where)
        sql += f" ORDER BY id {order}"
        if limit is not None:
            sql += " LIMIT ?"
            params.append(max(0, int(limit)))
        try:
            with self._lock:
                rows = self._conn.execute(sql, params).fetchall()
        except sqlite3.DatabaseError as exc:
            raise _bad(self.path, f"cannot be read ({exc})") from exc
        entries = [row_to_entry(r) for r in rows]
        return entries[::-1] if order == "DESC" else entries

    def query(self, *, after_id: int = 0, kind: Kind | str | Iterable[Kind | str] | None = None,
              wall_from: float | None = None, wall_to: float | None = None,
              limit: int | None = None, to_id: int | None = None) -> list[Entry]:
        """Entries with ``after_id < id <= to_id``, of the given kind(s),
        ``wall_from <= wall < wall_to``, the first ``limit`` of them."""
        where, params = self._where(after_id, kind, wall_from, wall_to, to_id)
        return self._select(where, params, "ASC", limit)

    def tail(self, n: int, kind: Kind | str | Iterable[Kind | str] | None = None, *,
             after_id: int = 0, to_id: int | None = None) -> list[Entry]:
        """The last ``n`` entries (of the given kinds, with ``after_id < id <= to_id``),
        oldest first."""
        where, params = self._where(after_id, kind, None, None, to_id)
        return self._select(where, params, "DESC", n)

    def since(self, after_id: int, limit: int | None = 1000,
              kind: Kind | str | Iterable[Kind | str] | None = None) -> list[Entry]:
        """Entries after ``after_id``: what a follower has not seen yet."""
        return self.query(after_id=after_id, kind=kind, limit=limit)

    def between(self, wall_from: float, wall_to: float,
                kind: Kind | str | Iterable[Kind | str] | None = None) -> list[Entry]:
        """Entries with ``wall_from <= wall < wall_to``."""
        return self.query(kind=kind, wall_from=wall_from, wall_to=wall_to)

    @staticmethod
    def _where(after_id: int, kind: Kind | str | Iterable[Kind | str] | None,
               wall_from: float | None, wall_to: float | None,
               to_id: int | None = None) -> tuple[list[str], list[Any]]:
        where: list[str] = ["id > ?"]
        params: list[Any] = [after_id]
        if to_id is not None:
            where.append("id <= ?")
            params.append(to_id)
        kinds = _kinds(kind)
        if kinds is not None:
            where.append(f"kind IN ({','.join('?' * len(kinds))})")
            params.extend(kinds)
        if wall_from is not None:
            where.append("wall >= ?")
            params.append(wall_from)
        if wall_to is not None:
            where.append("wall < ?")
            params.append(wall_to)
        return where, params

    def last_id(self) -> int:
        with self._lock:
            row = self._conn.execute("SELECT max(id) FROM entries").fetchone()
        return int(row[0] or 0)

    def span(self, after_id: int = 0, to_id: int | None = None
             ) -> tuple[int, int, float, float] | None:
        """``(entries, last id, first wall, last wall)`` of the ids in ``after_id < id <=
        to_id``; None when there are none."""
        sql = "SELECT count(*), max(id), min(wall), max(wall) FROM entries WHERE id > ?"
        params: list[Any] = [after_id]
        if to_id is not None:
            sql += " AND id <= ?"
            params.append(to_id)
        with self._lock:
            n, last, w0, w1 = self._conn.execute(sql, params).fetchone()
        return None if not n else (int(n), int(last), float(w0), float(w1))

    def counts(self) -> dict[str, int]:
        """Entries per kind (every kind listed, zero included)."""
        with self._lock:
            rows = self._conn.execute("SELECT kind, count(*) FROM entries GROUP BY kind")
            found = {str(k): int(n) for k, n in rows}
        return {k.value: found.get(k.value, 0) for k in Kind}

    def size_bytes(self) -> int:
        """The file plus its write-ahead log, in bytes (what the disk holds now)."""
        total = 0
        for suffix in ("", "-wal"):
            with contextlib.suppress(FileNotFoundError):
                total += os.stat(f"{self.path}{suffix}").st_size
        return total
