"""A memory probe for the daemon, off unless ``$DXBOARD_MEMPROBE`` names a directory.

When it does, ``install(on_signal)`` starts ``tracemalloc`` (``$DXBOARD_MEMPROBE_FRAMES`` frames per
allocation, default 1) and, on every SIGUSR2, writes into that directory the next numbered
``tracemalloc`` snapshot (``snap-N.tracemalloc``, for ``Snapshot.load`` and ``compare_to``) and
the live objects counted by type after a full collection (``types-N.json``). This is how
``benchmarks/memory.py`` tells a leak (what grows with every fault) from a high-water mark.
When the variable is unset nothing is imported, started or installed: it costs nothing.
"""

from __future__ import annotations

import collections
import gc
import json
import logging
import os
import signal
from collections.abc import Callable
from pathlib import Path

log = logging.getLogger(__name__)

ENV = "DXBOARD_MEMPROBE"


def install(on_signal: Callable[[int, Callable[[], None]], None]) -> Path | None:
    """Start the probe if ``$DXBOARD_MEMPROBE`` is set; the directory it writes to, or None.
    ``on_signal(signum, callback)`` routes a signal to a callback on the loop (the daemon's
    ``host.launch.signals.StopSignals.on``, or ``loop.add_signal_handler``)."""
    where = os.environ.get(ENV)
    if not where:
        return None
    import tracemalloc

    out = Path(where)
    out.mkdir(parents=True, exist_ok=True)
    tracemalloc.start(int(os.environ.get(ENV + "_FRAMES", "1")))
    count = [0]

    def dump() -> None:
        count[0] += 1
        gc.collect()
        types = collections.Counter(type(o).__qualname__ for o in gc.get_objects())
        (out / f"types-{count[0]}.json").write_text(json.dumps(dict(types.most_common(200))))
        tracemalloc.take_snapshot().dump(str(out / f"snap-{count[0]}.tracemalloc"))
        log.warning("memory probe: snapshot %d written to %s", count[0], out)

    on_signal(signal.SIGUSR2, dump)
    log.warning("memory probe on: tracemalloc started; SIGUSR2 writes a snapshot to %s", out)
    return out
