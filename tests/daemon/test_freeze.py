"""After start-up the daemon keeps its long-lived objects out of the cyclic collector's walk
(issue 30 item 5): a full collection holds the GIL and so stops the event loop even while a
diagnosis runs in its thread; with a large model it took longer than the board link's 0.25 s
deadline (benchmarks/stall.py measures it). In-process: no daemon is started here."""

from __future__ import annotations

import gc

from host.daemon.core import freeze_long_lived


class Node:
    """A stand-in for the model's objects: tracked by the collector, part of a cycle."""

    def __init__(self) -> None:
        self.me = self


def _tracked(obj: object) -> bool:
    return any(o is obj for o in gc.get_objects())


def test_what_exists_at_start_up_is_frozen_what_comes_later_is_collected() -> None:
    model = [Node() for _ in range(1000)]
    assert _tracked(model)
    try:
        freeze_long_lived()
        assert not _tracked(model)
        assert gc.get_freeze_count() >= len(model)
        later = Node()
        assert _tracked(later)
        del later
        assert gc.collect() >= 1  # the new cycle is still garbage the collector finds
    finally:
        gc.unfreeze()
    assert _tracked(model)
