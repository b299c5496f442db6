"""A stop in stages, each with a deadline, that says what it cut short.

A daemon's stop closes many things in turn (its tasks and the board link, the nodes, the topic
source, the web page, the journal's last commit, the emulated board). Any of them can hang: a
board that is silent or talks garbage, a middleware whose close blocks, a task that swallowed
its cancellation (issue 25, item 2: "still stopping … waiting for the daemon to close the web
page" for 31 minutes). ``StopStages(budget_s)`` runs each stage under the smaller of its own
cap and what is left of the whole budget:

- ``await stages.run(name, work, cap_s, on_cut=None)``: ``work`` is an awaitable (run as a
  task) or a plain callable (a blocking close, run on a daemon thread so that it cannot hold
  the loop up). At the deadline the task is cancelled and given ``GRACE_S`` more; ``on_cut()``
  is the stage's escalation (e.g. SIGKILL to the nodes' process groups); then the stop goes on
  without it, and ``cut`` and the log name the stage, so a person knows what did not end
  cleanly. A stage that raises is logged and the stop goes on too.
- ``current`` is the stage running now (``host.launch.stopping`` reports it while it waits).

The budget is what lets the whole stop stay under ``host.launch.signals.DEADLINE_S``, which
kills whatever is left: the stages end first, in order, in the normal case.
"""

from __future__ import annotations

import asyncio
import contextlib
import logging
import threading
import time
from collections.abc import Awaitable, Callable
from typing import Any

log = logging.getLogger(__name__)

GRACE_S = 0.5  # a cancelled stage's time to unwind
MIN_S = 0.2  # a stage's time even when the budget is spent


def in_thread(fn: Callable[[], Any], name: str) -> asyncio.Future[Any]:
    """Run the blocking ``fn`` on a daemon thread of its own; a future of its result. (Not the
    default executor: asyncio joins its threads at exit, and a stuck close would hang there.)"""
    loop = asyncio.get_running_loop()
    fut: asyncio.Future[Any] = loop.create_future()

    def settle(exc: BaseException | None, value: Any) -> None:
        if fut.done():
            return
        if exc is None:
            fut.set_result(value)
        else:
            fut.set_exception(exc)

    def run() -> None:
        try:
            value = fn()
        except BaseException as exc:
            with contextlib.suppress(RuntimeError):
                loop.call_soon_threadsafe(settle, exc, None)
        else:
            with contextlib.suppress(RuntimeError):
                loop.call_soon_threadsafe(settle, None, value)

    threading.Thread(target=run, name=f"close:{name}", daemon=True).start()
    return fut


class StopStages:
    def __init__(self, budget_s: float, clock: Callable[[], float] = time.monotonic) -> None:
        self.budget_s = budget_s
        self.clock = clock
        self.t0 = clock()
        self.current = ""
        self.cut: list[str] = []  # stages cut short, in order

    def left(self) -> float:
        return max(MIN_S, self.budget_s - (self.clock() - self.t0))

    async def run(self, name: str, work: Awaitable[Any] | Callable[[], Any], cap_s: float,
                  on_cut: Callable[[], None] | None = None, reserve_s: float = 0.0) -> bool:
        """Run one stage; True when it ended within its deadline. ``reserve_s`` of the budget
        is kept for the stages after it (the journal's last commit)."""
        self.current = name
        limit = min(cap_s, max(MIN_S, self.left() - reserve_s))
        task: asyncio.Future[Any] = (asyncio.ensure_future(work) if not callable(work)
                                     else in_thread(work, name))
        done, _ = await asyncio.wait({task}, timeout=limit)
        if done:
            if not task.cancelled() and task.exception() is not None:
                log.warning("stop: closing %s failed: %r", name, task.exception())
            return True
        task.cancel()
        await asyncio.wait({task}, timeout=GRACE_S)
        if on_cut is not None:
            try:
                on_cut()
            except Exception:
                log.exception("stop: cutting %s short failed", name)
        if task.done() and not task.cancelled():
            task.exception()  # retrieved: an abandoned stage is not "never retrieved" noise
        self.cut.append(name)
        log.warning("stop: %s did not close within %.1f s: cut short", name, limit)
        return False
