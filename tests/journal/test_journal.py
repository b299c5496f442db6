"""The journal round-trips every kind, answers its queries, keeps ids monotonic and prunes.

Each test writes through a real ``Journal`` on a temporary SQLite file and reads back through
the ``JournalReader`` (or a second reader on the same file, as the web page and the
``dxboard journal`` command do), with wall and monotonic times given by the test.
"""

from __future__ import annotations

import asyncio
import sqlite3
from pathlib import Path

import pytest

from host.errors import UserError
from host.journal import (
    ActionRecord,
    ActionState,
    BoardEvent,
    ChannelSummary,
    DiagnosisRecord,
    Journal,
    JournalReader,
    Kind,
    Note,
    Observation,
    PlanRecord,
    PlanStep,
    Retention,
    Telemetry,
)

T0 = 1_800_000_000.0

ONE_OF_EACH = [
    Observation("ok(hokuyo_node)", False, "topic:/scan"),
    Observation("running(hokuyo_node)", None, "process"),
    DiagnosisRecord.of([frozenset({"hokuyo", "hokuyo_node"}), ["hokuyo_node"]],
                       complete=False, trigger="observation", elapsed_s=0.012,
                       probabilities=[0.3, 0.7]),
    PlanRecord("p1", (PlanStep("power_up", ("hokuyo",)), PlanStep("start_node", ("hokuyo_node",))),
               ("hokuyo", "hokuyo_node")),
    ActionRecord("a1", "power_up", ("hokuyo",), ActionState.STARTED, T0 + 3),
    ActionRecord("a1", "power_up", ("hokuyo",), ActionState.SUCCEEDED, T0 + 3, T0 + 4.5, "p1",
                 "current 640 mA"),
    BoardEvent("trip", 3, {"reason": "i2t", "peak_ma": 4100}),
    Telemetry(1.0, (ChannelSummary(3, 100, 612.3, 590.0, 650.0, 611.0),)),
    Note("daemon started"),
]


def test_every_kind_round_trips_with_ids_and_times(tmp_path: Path) -> None:
    path = tmp_path / "j.sqlite"
    with Journal(path) as journal:
        ids = [journal.record(p, wall=T0 + i, mono=50.0 + i) for i, p in enumerate(ONE_OF_EACH)]
        assert journal.flush_blocking(timeout=10) == ids[-1]
    assert ids == list(range(1, len(ONE_OF_EACH) + 1))
    with JournalReader(path) as reader:
        entries = reader.tail(100)
    assert [e.id for e in entries] == ids
    assert [e.payload for e in entries] == ONE_OF_EACH
    assert [(e.wall, e.mono) for e in entries] == [(T0 + i, 50.0 + i) for i in range(len(ids))]
    assert entries[2].payload.diagnoses == (("hokuyo", "hokuyo_node"), ("hokuyo_node",))
    assert entries[0].to_json()["data"] == {"literal": "ok(hokuyo_node)", "value": False,
                                            "source": "topic:/scan"}


def test_queries_tail_since_kind_and_time_range(tmp_path: Path) -> None:
    with Journal(tmp_path / "j.sqlite") as journal:
        for i in range(30):
            payload = (Observation(f"ok(c{i})", i % 2 == 0) if i % 3
                       else Telemetry(1.0, (ChannelSummary(0, 1, i, i, i, i),)))
            journal.record(payload, wall=T0 + i, mono=float(i))
        journal.flush_blocking(timeout=10)
        r = journal.reader
        assert [e.id for e in r.tail(3)] == [28, 29, 30]
        assert [e.id for e in r.tail(2, kind="telemetry")] == [25, 28]
        assert [e.id for e in r.since(26)] == [27, 28, 29, 30]
        assert [e.id for e in r.since(0, limit=2)] == [1, 2]
        assert [e.id for e in r.since(20, kind=[Kind.TELEMETRY, "observation"], limit=3)] == [
            21, 22, 23]
        assert [e.id for e in r.between(T0 + 10, T0 + 13)] == [11, 12, 13]
        assert [e.id for e in r.between(T0 + 10, T0 + 13, kind="telemetry")] == [13]
        assert r.counts()["telemetry"] == 10 and r.counts()["observation"] == 20
        assert r.counts()["plan"] == 0
        assert r.last_id() == 30
        assert r.size_bytes() > 0
        with pytest.raises(ValueError):
            r.tail(1, kind="nonsense")


def test_ids_stay_monotonic_across_reopen_even_after_pruning_the_newest(tmp_path: Path) -> None:
    path = tmp_path / "j.sqlite"
    with Journal(path, retention=Retention(telemetry_max_rows=0)) as journal:
        journal.record(Note("a"), wall=T0, mono=0.0)
        for i in range(3):
            journal.record(Telemetry(1.0, ()), wall=T0 + i, mono=float(i))
        journal.flush_blocking(timeout=10)
        assert journal.prune(T0 + 5) == 3
        assert journal.reader.last_id() == 1
    with Journal(path) as journal:
        assert journal.record(Note("b"), wall=T0 + 9, mono=9.0) == 5
        journal.flush_blocking(timeout=10)
        assert [e.id for e in journal.reader.tail(10)] == [1, 5]


def test_retention_prunes_old_and_excess_telemetry_and_keeps_every_other_kind(
        tmp_path: Path) -> None:
    retention = Retention(telemetry_max_age_s=100.0, telemetry_max_rows=50, prune_every=10)
    with Journal(tmp_path / "j.sqlite", retention=retention) as journal:
        for i in range(300):  # five minutes at 1 Hz, an observation every 10 s
            journal.record(Telemetry(1.0, (ChannelSummary(1, 100, 5, 4, 6, 5),)),
                           wall=T0 + i, mono=float(i))
            if i % 10 == 0:
                journal.record(Observation("ok(x)", i % 20 == 0), wall=T0 + i, mono=float(i))
            if i % 50 == 0:
                journal.flush_blocking(timeout=10)  # several batches, so pruning runs in between
        journal.flush_blocking(timeout=10)
        journal.prune(T0 + 299)
        telemetry = journal.reader.query(kind="telemetry")
        counts = journal.reader.counts()
    assert counts["observation"] == 30
    assert len(telemetry) == 50
    assert telemetry[-1].wall == T0 + 299 and telemetry[0].wall == T0 + 250


def test_pruning_by_age_uses_the_given_time(tmp_path: Path) -> None:
    with Journal(tmp_path / "j.sqlite", retention=Retention(telemetry_max_age_s=60)) as journal:
        for i in range(10):
            journal.record(Telemetry(1.0, ()), wall=T0 + 10 * i, mono=float(i))
        journal.flush_blocking(timeout=10)
        assert journal.prune(T0 + 90) == 3  # walls T0+0, +10, +20 are older than 60 s
        assert journal.prune(T0 + 90) == 0


async def test_async_flush_waits_for_the_commit_without_blocking_the_loop(
        tmp_path: Path) -> None:
    journal = Journal(tmp_path / "j.sqlite")
    try:
        ticks = 0

        async def ticker() -> None:
            nonlocal ticks
            while True:
                ticks += 1
                await asyncio.sleep(0)

        task = asyncio.create_task(ticker())
        last = 0
        for i in range(2000):
            last = journal.record(Observation(f"ok(c{i % 7})", True), wall=T0 + i, mono=float(i))
        assert await journal.flush() == last == 2000
        task.cancel()
        assert journal.committed_id == 2000
        assert journal.pending == 0
        assert ticks > 0  # the loop kept running while the writer thread committed
        assert len(journal.reader.since(0, limit=None)) == 2000
    finally:
        await asyncio.to_thread(journal.close)
    journal.close()  # idempotent
    with pytest.raises(RuntimeError):
        journal.record(Note("late"), wall=T0, mono=0.0)


def test_a_payload_that_is_not_json_fails_at_the_call(tmp_path: Path) -> None:
    with Journal(tmp_path / "j.sqlite") as journal:
        with pytest.raises(ValueError):
            journal.record(BoardEvent("x", None, {"bad": float("nan")}), wall=T0, mono=0.0)
        assert journal.record(Note("fine"), wall=T0, mono=0.0) == 1


def _error(path: Path, create: bool = True) -> str:
    with pytest.raises(UserError) as info:
        if create:
            Journal(path).close()
        else:
            JournalReader(path).close()
    text = str(info.value)
    assert "\n" not in text and str(path) in text
    return text


def test_bad_files_are_one_line_user_errors(tmp_path: Path) -> None:
    garbage = tmp_path / "garbage.sqlite"
    garbage.write_bytes(b"this is not a database at all, just some text\n" * 100)
    assert "not a dxboard journal" in _error(garbage) and "new file name" in _error(garbage)

    other = tmp_path / "other.sqlite"
    with sqlite3.connect(other) as conn:
        conn.execute("CREATE TABLE t (x)")
    conn.close()
    assert "another program" in _error(other)

    newer = tmp_path / "newer.sqlite"
    Journal(newer).close()
    with sqlite3.connect(newer) as conn:
        conn.execute("PRAGMA user_version=99")
    conn.close()
    assert "upgrade dxboard" in _error(newer)

    assert "is a directory" in _error(tmp_path)
    assert "does not exist" in _error(tmp_path / "nowhere" / "j.sqlite")
    assert "no such file" in _error(tmp_path / "missing.sqlite", create=False)
    assert not (tmp_path / "missing.sqlite").exists()


def test_a_damaged_row_reads_as_an_error_note_not_a_crash(tmp_path: Path) -> None:
    path = tmp_path / "j.sqlite"
    with Journal(path) as journal:
        journal.record(Observation("ok(a)", True), wall=T0, mono=0.0)
        journal.record(Observation("ok(b)", True), wall=T0, mono=0.0)
    with sqlite3.connect(path) as conn:
        conn.execute("UPDATE entries SET data = '{\"nope\": 1}' WHERE id = 1")
    conn.close()
    with JournalReader(path) as reader:
        first, second = reader.tail(2)
    assert isinstance(first.payload, Note) and first.payload.level == "error"
    assert first.id == 1 and second.payload == Observation("ok(b)", True)


def test_telemetry_is_stored_compactly_to_a_tenth_of_a_milliampere() -> None:
    t = Telemetry(1.0, (ChannelSummary(3, 100, 612.34567, 590.0, 650.04, 611.0),))
    assert t.to_json() == {"period_s": 1.0, "channels": [[3, 100, 612.3, 590.0, 650.0, 611.0]]}


def test_an_empty_file_is_not_taken_for_a_journal_by_a_reader(tmp_path: Path) -> None:
    empty = tmp_path / "empty.sqlite"
    empty.write_bytes(b"")
    assert "is empty" in _error(empty, create=False)
    with Journal(empty) as journal:  # the writer may start a journal in an empty file
        assert journal.record(Note("first"), wall=T0, mono=0.0) == 1


def test_when_the_file_cannot_be_written_entries_wait_and_overflow_is_recorded(
        tmp_path: Path, caplog: pytest.LogCaptureFixture) -> None:
    path = tmp_path / "j.sqlite"
    Journal(path).close()
    blocker = sqlite3.connect(path, isolation_level=None)
    blocker.execute("BEGIN EXCLUSIVE")  # another writer holds the file: every commit fails
    journal = Journal(path, max_pending=5, busy_timeout_s=0.05)
    try:
        for i in range(8):
            journal.record(Observation(f"ok(c{i + 1})", True), wall=T0 + i, mono=float(i))
        with pytest.raises(TimeoutError):
            journal.flush_blocking(timeout=0.5)
        assert journal.dropped == 3 and journal.pending == 5
        assert "dropped entry 1" in caplog.text and "cannot commit" in caplog.text
        blocker.execute("COMMIT")
        journal.flush_blocking(timeout=20)
        journal.flush_blocking(timeout=20)  # the note about the loss, recorded after it
        entries = journal.reader.since(0, limit=None)
    finally:
        blocker.close()
        journal.close()
    assert [e.id for e in entries] == [4, 5, 6, 7, 8, 9]
    note = entries[-1].payload
    assert isinstance(note, Note) and note.level == "error"
    assert note.text == "journal dropped 3 entries waiting for the disk (ids 1..3)"
