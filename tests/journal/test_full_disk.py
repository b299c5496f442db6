"""The journal on a real full disk (a tmpfs the test mounts): nothing blocks, nothing is lost.

``record`` never waits for the disk; while commits fail the entries are held in memory and
``health()`` says ``disk full`` and how many; the terminal gets one line when it starts failing
and one when it writes again (with the count); once the space is back the backlog is written
without anyone asking, every entry in order.
"""

from __future__ import annotations

import logging
import time
from pathlib import Path

import pytest

from benchmarks._rigs.fulldisk import small_disk
from host.events import Note
from host.journal import Journal
from tests.wait import wait_until

T0 = 1_700_000_000.0
BIG = "x" * 2000  # a few entries fill what a full tmpfs has left in its last pages


def test_a_full_disk_holds_entries_in_memory_and_writes_them_when_space_returns(
        tmp_path: Path, caplog: pytest.LogCaptureFixture) -> None:
    with small_disk(tmp_path / "disk") as disk:
        journal = Journal(disk.path / "j.sqlite")
        try:
            journal.record(Note("before"), wall=T0, mono=0.0)
            journal.flush_blocking(timeout=30)
            disk.fill()
            n = 200
            with caplog.at_level(logging.DEBUG, logger="host.journal"):
                started = time.monotonic()
                for i in range(n):
                    journal.record(Note(f"held {i} {BIG}"), wall=T0 + i, mono=float(i))
                recording = time.monotonic() - started
                problem, held, dropped = wait_until(
                    lambda: journal.health() if journal.health()[0] else None, 30,
                    "the journal to say the disk is full")
                assert problem == "disk full" and held > 0 and dropped == 0
                assert recording < 5.0  # never waits for the disk (generous: a busy machine)
                disk.free()
                journal.flush_blocking(timeout=60)
            assert journal.health() == ("", 0, 0)
            entries = journal.reader.since(0, limit=None)
        finally:
            journal.close()
    texts = [e.payload.text for e in entries if isinstance(e.payload, Note)]
    assert texts == ["before", *(f"held {i} {BIG}" for i in range(n))]
    errors = [r.getMessage() for r in caplog.records if r.levelno >= logging.WARNING]
    assert len(errors) == 2, errors
    assert "disk full" in errors[0] and "holding entries in memory" in errors[0]
    assert "writing again" in errors[1] and "entries held" in errors[1]


def test_closing_on_a_full_disk_ends_and_says_what_was_not_written(
        tmp_path: Path, caplog: pytest.LogCaptureFixture) -> None:
    with small_disk(tmp_path / "disk") as disk:
        journal = Journal(disk.path / "j.sqlite")
        try:
            disk.fill()
            for i in range(50):
                journal.record(Note(f"held {i} {BIG}"), wall=T0 + i, mono=float(i))
            wait_until(lambda: journal.health()[0], 30, "the journal to say the disk is full")
        finally:
            journal.close()  # returns: a few quick retries, then it gives up and says so
    assert "closing with" in caplog.text and "entries not written (disk full)" in caplog.text
