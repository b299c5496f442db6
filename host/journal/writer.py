"""The journal's writer: a thread that commits what the daemon records, in batches.

Why a thread: SQLite calls block, and a commit with ``synchronous=FULL`` waits for an fsync
(milliseconds on a good disk, hundreds on a busy SD card). ``Journal.record`` only assigns the
next id, encodes the payload and appends it to a queue under a lock (microseconds), so the
asyncio loop never waits for the disk. The writer thread takes everything queued, writes it in
one transaction and commits: a group commit whose batches grow by themselves when the disk is
slow, so a burst costs one fsync, not one per entry. ``await journal.flush()`` (or
``flush_blocking``) returns once everything recorded so far is committed, i.e. on disk:
nothing committed is lost on kill -9, nor (with the default ``sync="full"``) on power loss.
Nothing is dropped silently, and a failing disk never blocks the daemon: if a commit fails
(a full disk: SQLite's "database or disk is full", or any ``OSError``), the batch stays queued
in memory and is retried with a back-off of at most ``MAX_BACKOFF_S`` (so it is written within
about a second of space returning), counted in ``write_failures``; the terminal gets one ERROR
line when writing starts failing and one line when it works again, with the number of entries
that were held, and ``health()`` says what fails and how many entries are held, for the
page, the API and ``/diagnostics`` (``host.daemon.journalwatch``). Only when more than
``max_pending`` entries wait are the oldest dropped, counted in ``dropped``, logged once, and
recorded as an error note once writing works again.
Retention runs in the same thread: every ``prune_every`` telemetry entries, telemetry older than
``Retention.telemetry_max_age_s`` before the newest recorded wall time (the daemon's time, never
read here) or beyond ``telemetry_max_rows`` is deleted; every other kind is kept.
"""

from __future__ import annotations

import asyncio
import fcntl
import json
import logging
import os
import sqlite3
import threading
import time
from collections import deque
from dataclasses import dataclass
from pathlib import Path
from typing import IO

from host.errors import UserError
from host.events import Kind, Note, Payload
from host.journal.store import JournalReader, connect

log = logging.getLogger(__name__)

_Row = tuple[int, str, float, float, str]

MAX_BACKOFF_S = 1.0  # the longest wait between retries of a failing commit
CLOSE_RETRIES = 3  # a closing journal that still cannot write gives up after these


def problem_of(exc: BaseException) -> str:
    """What a failed commit says to a person: ``disk full`` or the error itself."""
    code = getattr(exc, "sqlite_errorcode", None)
    if code == sqlite3.SQLITE_FULL or getattr(exc, "errno", None) == 28 \
            or "disk is full" in str(exc) or "No space left" in str(exc):
        return "disk full"
    return f"cannot write ({exc})"


def _writer_lock(path: Path) -> IO[str]:
    """Hold ``<journal>.lock`` for as long as this writer lives: one writer per journal. Two
    daemons writing one file would number their entries alike and lose them."""
    lock = path.with_name(path.name + ".lock").open("a+")
    try:
        fcntl.flock(lock, fcntl.LOCK_EX | fcntl.LOCK_NB)
    except OSError:
        lock.seek(0)
        holder = lock.read().strip() or "another process"
        lock.close()
        raise UserError(f"{path}: the journal is in use by {holder}",
                        "stop that dxboard run, or give this one another --journal") from None
    lock.seek(0)
    lock.truncate()
    lock.write(f"pid {os.getpid()}\n")
    lock.flush()
    return lock


@dataclass(frozen=True)
class Retention:
    """How much telemetry to keep; other kinds are never pruned."""

    telemetry_max_age_s: float = 24 * 3600.0
    telemetry_max_rows: int = 200_000
    prune_every: int = 60


class Journal:
    """The write side (and, through ``reader``, the read side) of one journal file."""

    def __init__(self, path: str | os.PathLike[str], *, retention: Retention | None = None,
                 sync: str = "full", max_pending: int = 100_000,
                 busy_timeout_s: float = 10.0) -> None:
        if sync not in ("full", "normal"):
            raise ValueError(f"sync must be 'full' or 'normal', not {sync!r}")
        self.path = Path(path)
        self.retention = retention or Retention()
        self.max_pending = max_pending
        self._conn = connect(path, create=True, sync=sync, busy_timeout_s=busy_timeout_s)
        try:
            self._lock = _writer_lock(self.path)  # after connect: its errors name a bad path
        except BaseException:
            self._conn.close()
            raise
        try:
            self.reader = JournalReader(path, connect(path, create=False))
            row = self._conn.execute(
                "SELECT seq FROM sqlite_sequence WHERE name = 'entries'").fetchone()
        except BaseException:
            self._lock.close()
            self._conn.close()
            raise
        self._next_id = int(row[0]) + 1 if row else 1
        self._committed_id = self._next_id - 1
        self._queue: deque[_Row] = deque()
        self._cond = threading.Condition()
        self._waiters: list[tuple[int, asyncio.AbstractEventLoop, asyncio.Future[int]]] = []
        self._closing = False
        self._closed = False
        self._wake = threading.Event()  # ends a retry's back-off early (close)
        self.dropped = 0
        self.recorded = 0  # entries recorded by this writer (ids are given without gaps)
        self.write_failures = 0  # commits that failed (and were retried), for the metrics
        self._dropped_ids: list[int] = []
        self._problem = ""  # why commits fail now ("" while they work)
        self._telemetry_since_prune = 0
        self._newest_wall = 0.0
        self._newest_mono = 0.0
        self._db = threading.Lock()  # one transaction at a time on the writer's connection
        self._thread = threading.Thread(target=self._run, name=f"journal:{self.path.name}",
                                        daemon=True)
        self._thread.start()

    # --- the daemon's side ----------------------------------------------------------------

    def record(self, payload: Payload, *, wall: float, mono: float) -> int:
        """Queue one entry with the daemon's wall and monotonic times; returns its id."""
        data = json.dumps(payload.to_json(), separators=(",", ":"), allow_nan=False)
        with self._cond:
            if self._closing:
                raise RuntimeError(f"journal {self.path} is closed")
            ident = self._next_id
            self._next_id += 1
            self.recorded += 1
            self._queue.append((ident, payload.kind.value, wall, mono, data))
            if len(self._queue) > self.max_pending:
                lost = self._queue.popleft()
                self.dropped += 1
                self._dropped_ids.append(lost[0])
                if len(self._dropped_ids) == 1:  # once per overflow, not once per entry
                    log.error("journal %s: %d entries waiting for the disk; dropped entry %d "
                              "(%s), and each older one after it (counted)",
                              self.path, len(self._queue), lost[0], lost[1])
            self._cond.notify()
        return ident

    @property
    def committed_id(self) -> int:
        """The highest id known to be committed (every lower id is committed too)."""
        with self._cond:
            return self._committed_id

    @property
    def pending(self) -> int:
        with self._cond:
            return len(self._queue)

    def health(self) -> tuple[str, int, int]:
        """``(problem, held, dropped)``: why commits fail ("" while they work), the entries
        waiting in memory, and those lost beyond ``max_pending``."""
        with self._cond:
            return self._problem, len(self._queue), self.dropped

    async def flush(self) -> int:
        """Wait until every entry recorded so far is committed; returns the last id."""
        loop = asyncio.get_running_loop()
        with self._cond:
            target = self._next_id - 1
            if self._committed_id >= target:
                return self._committed_id
            if self._closed:
                raise RuntimeError(f"journal {self.path} is closed")
            fut: asyncio.Future[int] = loop.create_future()
            self._waiters.append((target, loop, fut))
            self._cond.notify()
        return await fut

    def flush_blocking(self, timeout: float | None = None) -> int:
        """``flush`` for synchronous callers (the CLI, tests, shutdown)."""
        deadline = None if timeout is None else time.monotonic() + timeout
        with self._cond:
            target = self._next_id - 1
            while self._committed_id < target:
                left = None if deadline is None else deadline - time.monotonic()
                if (left is not None and left <= 0) or self._closed:
                    raise TimeoutError(f"journal {self.path}: entries up to {target} "
                                       f"not committed yet (at {self._committed_id})")
                self._cond.wait(left)
            return self._committed_id

    def prune(self, now_wall: float) -> int:
        """Delete telemetry beyond the retention as of ``now_wall``; returns rows deleted."""
        with self._db:
            return self._prune(now_wall)

    def close(self) -> None:
        """Commit what is queued, stop the thread, close the files. Idempotent."""
        with self._cond:
            if self._closing:
                already = True
            else:
                already = False
                self._closing = True
                self._wake.set()
                self._cond.notify_all()
        if not already:
            self._thread.join()
            self.reader.close()
            self._conn.close()
            self._lock.close()  # releases the lock

    async def __aenter__(self) -> Journal:
        return self

    async def __aexit__(self, *exc: object) -> None:
        await asyncio.to_thread(self.close)

    def __enter__(self) -> Journal:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    # --- the writer thread ----------------------------------------------------------------

    def _run(self) -> None:
        backoff = 0.0
        closing_failures = 0
        while True:
            with self._cond:
                while not self._queue and not self._closing:
                    self._cond.wait()
                if not self._queue and self._closing:
                    break
                batch = list(self._queue)
            try:
                with self._db:
                    self._write(batch)
            except (sqlite3.Error, OSError) as exc:
                self.write_failures += 1
                backoff = min(MAX_BACKOFF_S, backoff * 2 or 0.1)
                self._failed(exc, len(batch))
                if self._closing:
                    closing_failures += 1
                    if closing_failures >= CLOSE_RETRIES:
                        log.error("journal %s: closing with %d entries not written (%s)",
                                  self.path, len(batch), self._problem)
                        break
                self._wake.wait(backoff)  # set by close(): it need not sit out the back-off
                continue
            backoff = 0.0
            self._committed(batch)
        with self._cond:
            self._closed = True
            self._cond.notify_all()
            waiters, self._waiters = self._waiters, []
        for _target, loop, fut in waiters:
            loop.call_soon_threadsafe(_fail, fut, RuntimeError("journal closed"))

    def _failed(self, exc: BaseException, waiting: int) -> None:
        problem = problem_of(exc)
        with self._cond:
            first = not self._problem
            self._problem = problem
        if first:
            log.error("journal %s: cannot commit (%s); holding entries in memory (up to %d) "
                      "and retrying",
                      self.path, problem, self.max_pending)
        else:
            log.debug("journal %s: still %s, %d entries held", self.path, problem, waiting)

    def _write(self, batch: list[_Row]) -> None:
        conn = self._conn
        conn.execute("BEGIN IMMEDIATE")
        try:
            conn.executemany(
                "INSERT INTO entries (id, kind, wall, mono, data) VALUES (?, ?, ?, ?, ?)", batch)
            conn.execute("COMMIT")
        except BaseException:
            if conn.in_transaction:
                conn.execute("ROLLBACK")
            raise

    def _committed(self, batch: list[_Row]) -> None:
        telemetry = sum(1 for r in batch if r[1] == Kind.TELEMETRY.value)
        newest = max(r[2] for r in batch)
        newest_mono_batch = max(r[3] for r in batch)
        with self._cond:
            # the batch is the head of the queue unless record() dropped some of it meanwhile
            done = {r[0] for r in batch}
            while self._queue and self._queue[0][0] in done:
                self._queue.popleft()
            self._committed_id = max(self._committed_id, batch[-1][0])
            recovered = self._problem
            if recovered:
                log.warning("journal %s: writing again; the %d entries held while it was %s "
                            "are journalled", self.path, len(batch), recovered)
                self._problem = ""
            self._newest_wall = max(self._newest_wall, newest)
            self._newest_mono = max(self._newest_mono, newest_mono_batch)
            self._telemetry_since_prune += telemetry
            # an entry dropped from the queue while its batch was being written is on disk
            dropped = [i for i in self._dropped_ids if i not in done]
            self.dropped -= len(self._dropped_ids) - len(dropped)
            self._dropped_ids = []
            if dropped and not self._closing:
                # queued in the same critical section as the commit is published, so whoever
                # flushes after seeing the commit also waits for this note (the lock is an RLock)
                self.record(Note(f"journal dropped {len(dropped)} entries waiting for the disk "
                                 f"(ids {dropped[0]}..{dropped[-1]})", "error"),
                            wall=self._newest_wall, mono=self._newest_mono)
            ready = [w for w in self._waiters if w[0] <= self._committed_id]
            self._waiters = [w for w in self._waiters if w[0] > self._committed_id]
            committed = self._committed_id
            self._cond.notify_all()
            prune = self._telemetry_since_prune >= self.retention.prune_every
            if prune:
                self._telemetry_since_prune = 0
            newest_wall = self._newest_wall
        for _target, loop, fut in ready:
            loop.call_soon_threadsafe(_resolve, fut, committed)
        if prune:
            try:
                self.prune(newest_wall)
            except sqlite3.Error as exc:
                log.error("journal %s: pruning telemetry failed: %s", self.path, exc)

    def _prune(self, now_wall: float) -> int:
        r = self.retention
        conn = self._conn
        try:
            conn.execute("BEGIN IMMEDIATE")
            cur = conn.execute("DELETE FROM entries WHERE kind = ? AND wall < ?",
                               (Kind.TELEMETRY.value, now_wall - r.telemetry_max_age_s))
            deleted = cur.rowcount
            cur = conn.execute(
                "DELETE FROM entries WHERE kind = ? AND id <= (SELECT id FROM entries "
                "WHERE kind = ? ORDER BY id DESC LIMIT 1 OFFSET ?)",
                (Kind.TELEMETRY.value, Kind.TELEMETRY.value, r.telemetry_max_rows))
            deleted += cur.rowcount
            conn.execute("COMMIT")
        except BaseException:
            if conn.in_transaction:
                conn.execute("ROLLBACK")
            raise
        if deleted:
            log.info("journal %s: pruned %d telemetry entries", self.path, deleted)
        return deleted


def _resolve(fut: asyncio.Future[int], value: int) -> None:
    if not fut.done():
        fut.set_result(value)


def _fail(fut: asyncio.Future[int], exc: BaseException) -> None:
    if not fut.done():
        fut.set_exception(exc)
