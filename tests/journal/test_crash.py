"""Nothing committed is lost when the daemon is killed with SIGKILL.

A real child process (``crash_child``) writes entries through ``Journal`` and prints the id of
each entry once ``flush()`` says it is committed. The test waits until it has reported a few
hundred commits, kills it with SIGKILL while it is still writing, reopens the file and checks
that every entry the child reported is there, in order, with the content it was given, that
nothing after the last report is half-written, and that the file passes SQLite's integrity
check and accepts new entries with higher ids.
"""

from __future__ import annotations

import os
import signal
import sqlite3
import subprocess
import sys
from pathlib import Path

from host.journal import Journal, JournalReader, Note
from tests.journal.crash_child import expected

ROOT = Path(__file__).resolve().parents[2]


def test_kill_9_loses_nothing_that_was_reported_committed(tmp_path: Path) -> None:
    path = tmp_path / "crash.sqlite"
    child = subprocess.Popen(
        [sys.executable, "-m", "tests.journal.crash_child", str(path)], cwd=ROOT,
        stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    reported: list[int] = []
    try:
        assert child.stdout is not None
        for line in child.stdout:
            reported.append(int(line.split()[1]))
            if len(reported) >= 300:
                break
        os.kill(child.pid, signal.SIGKILL)
    finally:
        child.kill()
        child.wait(timeout=30)
    assert child.returncode == -signal.SIGKILL, child.stderr.read() if child.stderr else ""
    assert len(reported) == 300 and reported == sorted(reported)
    last_reported = reported[-1]
    assert last_reported > 300  # bursts of several entries were committed at once

    with JournalReader(path) as reader:
        entries = reader.since(0, limit=None)
    ids = [e.id for e in entries]
    assert ids == list(range(1, len(ids) + 1))  # in order, no gap, nothing torn
    assert len(ids) >= last_reported
    assert all(e.payload == expected(e.id) for e in entries)

    conn = sqlite3.connect(path)
    try:
        assert conn.execute("PRAGMA integrity_check").fetchone()[0] == "ok"
    finally:
        conn.close()
    with Journal(path) as journal:
        assert journal.record(Note("after the crash"), wall=0.0, mono=0.0) == len(ids) + 1
