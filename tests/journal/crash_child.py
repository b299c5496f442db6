"""A journal writer to kill: records entries forever and reports each committed id.

Run as ``python -m tests.journal.crash_child FILE``. It records bursts of entries whose content
follows from their id (``Observation(f"ok(c{id})", id % 2 == 0)``), awaits ``flush()`` after
each burst and prints ``committed N`` once entry N is on disk, then goes on until killed. The
parent (``test_crash.py``) kills it with SIGKILL mid-burst and checks the file.
"""

from __future__ import annotations

import asyncio
import sys

from host.journal import Journal, Observation


def expected(ident: int) -> Observation:
    return Observation(f"ok(c{ident})", ident % 2 == 0, "crash_child")


async def main(path: str) -> None:
    journal = Journal(path)
    burst = 1
    ident = 0  # a fresh file: ids count from 1
    while True:
        for _ in range(burst):
            ident += 1
            got = journal.record(expected(ident), wall=1_800_000_000.0 + ident, mono=float(ident))
            if got != ident:
                raise SystemExit(f"journal gave id {got}, expected {ident}")
        committed = await journal.flush()
        print(f"committed {committed}", flush=True)
        burst = burst % 50 + 1  # bursts of 1..50 entries


if __name__ == "__main__":
    asyncio.run(main(sys.argv[1]))
