"""The daemon's watch on its journal: a ``JournalHealth`` event when it cannot write, a recount
while it lasts, one when it writes again, and nothing while all is well."""

from __future__ import annotations

import asyncio
import contextlib

from host.daemon import journalwatch
from host.events import Event, JournalHealth


class FakeHealth:
    """Only the health figures (the writer itself is tested on a real full disk)."""

    def __init__(self) -> None:
        self.now = ("", 0, 0)

    def health(self) -> tuple[str, int, int]:
        return self.now


async def test_the_watch_says_a_full_disk_its_count_and_the_recovery() -> None:
    journal = FakeHealth()
    said: list[Event] = []
    task = asyncio.ensure_future(journalwatch.watch(journal, said.append))

    async def until(n: int) -> None:
        while len(said) < n:
            await asyncio.sleep(0.05)

    try:
        await asyncio.sleep(3 * journalwatch.PERIOD_S)
        assert said == []  # nothing to say while it writes
        journal.now = ("disk full", 5, 0)
        await asyncio.wait_for(until(1), 30)
        journal.now = ("disk full", 9, 0)
        await asyncio.wait_for(until(2), 30)  # recounted (at most once a second)
        journal.now = ("", 0, 0)
        await asyncio.wait_for(until(3), 30)
    finally:
        task.cancel()
        with contextlib.suppress(asyncio.CancelledError):
            await task
    assert said == [JournalHealth("disk full", 5, 0), JournalHealth("disk full", 9, 0),
                    JournalHealth("", 0, 0)]
