"""The loop and memory benchmarks' fault schedule (``benchmarks.loop.schedule``) holds exactly
the number of faults asked for, the kinds shared out evenly: ``benchmarks/memory.py --faults 1``
used to get an empty schedule and end in a traceback."""

from __future__ import annotations

from collections import Counter

from benchmarks.loop import KINDS, schedule


def test_every_count_gets_that_many_faults_the_kinds_shared_evenly() -> None:
    for n in range(0, 9):
        faults = schedule(n, seed=7)
        assert len(faults) == n
        per_kind = Counter(k for k, _ in faults)
        assert set(per_kind) <= set(KINDS)
        if n >= len(KINDS):
            assert max(per_kind.values()) - min(per_kind.values()) <= 1
        for kind, device in faults:
            assert device in KINDS[kind]
