"""Telling everyone that the daemon is behind: a ``LoopLag`` event when its loop runs late.

The metrics' lag probe (``host.fleet.metrics.LagProbe``) measures how late the daemon's event
loop wakes (the worst of its last ten 0.5 s sleeps). A loop that late is a daemon behind its
inputs: readings and messages wait, diagnoses and repairs come late, and what the page shows is
older than it looks (issue 25: "a daemon that falls behind says it is behind"). ``watch(probe,
emit)`` reads the probe every ``PERIOD_S`` and emits ``LoopLag`` when the daemon falls behind
(lag over ``LIMIT_S``, the fleet alert's threshold, ``DxboardDaemonBehind``) or catches up, and
while behind when the lag changed by ``RETELL_S`` or more (at most once per ``RECOUNT_S``), so
``/diagnostics`` (``dxboard daemon``: WARN with the lag) and the page's headline say it.
"""

from __future__ import annotations

import asyncio
import time
from collections.abc import Callable
from typing import Protocol

from host.events import Event, LoopLag

PERIOD_S = 0.5
LIMIT_S = 1.0  # as the fleet's DxboardDaemonBehind alert (deploy/prometheus/dxboard-rules.yml)
RETELL_S = 0.5
RECOUNT_S = 2.0


class Probe(Protocol):
    @property
    def lag_s(self) -> float: ...


def judge(lag_s: float, said: LoopLag | None, now: float, said_at: float,
          limit_s: float = LIMIT_S) -> LoopLag | None:
    """The event to emit now (None: nothing new to say). Pure, for the tests."""
    behind = lag_s > limit_s
    if said is None or behind != said.behind:
        return LoopLag(round(lag_s, 3), behind, limit_s)
    if behind and abs(lag_s - said.lag_s) >= RETELL_S and now - said_at >= RECOUNT_S:
        return LoopLag(round(lag_s, 3), behind, limit_s)
    return None


async def watch(probe: Probe, emit: Callable[[Event], None], *, limit_s: float = LIMIT_S,
                clock: Callable[[], float] = time.monotonic) -> None:
    """Emit ``LoopLag`` as the daemon falls behind and catches up (see the docstring)."""
    said: LoopLag | None = None
    said_at = 0.0
    while True:
        await asyncio.sleep(PERIOD_S)
        event = judge(probe.lag_s, said, clock(), said_at, limit_s)
        if event is not None:
            emit(event)
            said, said_at = event, clock()
