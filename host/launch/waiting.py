"""Waiting on a live system: poll a condition until it holds, with a generous deadline, never a
fixed sleep (the launcher's waits on the processes it starts, the tests', the benchmarks').

A test that sleeps a fixed time and then asserts ("it has happened by now") fails on a busy
machine. ``wait_until(probe, timeout, what)`` instead calls ``probe`` until it returns something
truthy and returns that value; at the deadline it raises ``AssertionError`` naming what was
awaited, how long, and what was seen last (the probe's last value, or ``show()`` when given).
``wait_until_async`` is the same on an event loop: the probe may be a coroutine function, and
``each`` runs every round (e.g. to re-publish, or to take a stream's next item; an awaited
``each`` or probe that never returns fails at the deadline too). Deadlines are generous on
purpose: they only decide how long a broken test takes to fail, never whether a working one
passes. A missed deadline is an ``AssertionError`` so that, in a test, it reads as the failure
it is.

Absence ("no repair was started") cannot be awaited; such a test first waits for evidence that
the thing under test had its chance (a later diagnosis, a later message), then asserts.
"""

from __future__ import annotations

import asyncio
import inspect
import time
from collections.abc import Awaitable, Callable
from typing import Any, TypeVar, cast

T = TypeVar("T")

TIMEOUT_S = 30.0  # the default deadline: a loaded 2-core machine is slow, not this slow


def _fail(what: str, timeout: float, last: object, show: Callable[[], object] | None) -> None:
    seen = show() if show is not None else last
    raise AssertionError(f"timed out after {timeout:g} s waiting for {what}; "
                         f"last seen: {seen!r}")


def wait_until(probe: Callable[[], T | None], timeout: float = TIMEOUT_S,
               what: str = "the condition", *, interval: float = 0.05,
               show: Callable[[], object] | None = None) -> T:
    """Poll ``probe`` until its value is truthy; return that value (sync)."""
    end = time.monotonic() + timeout
    while True:
        value = probe()
        if value:
            return value
        if time.monotonic() >= end:
            _fail(what, timeout, value, show)
        time.sleep(interval)


async def wait_until_async(probe: Callable[[], Awaitable[T]] | Callable[[], T],
                           timeout: float = TIMEOUT_S, what: str = "the condition", *,
                           interval: float = 0.05,
                           show: Callable[[], object] | None = None,
                           each: Callable[[], Any] | None = None) -> T:
    """Poll ``probe`` (a function or a coroutine function) until its value is truthy (async).

    ``each`` is called (and awaited, if it returns an awaitable) before every poll. Both are
    awaited within what is left of the deadline: one that never returns (a stream gone quiet)
    fails at the deadline like a condition that never holds."""
    loop = asyncio.get_running_loop()
    end = loop.time() + timeout
    value: Any = None

    async def within(step: Awaitable[Any]) -> Any:
        try:
            async with asyncio.timeout_at(end):
                return await step
        except TimeoutError:
            _fail(what, timeout, value, show)

    while True:
        if each is not None:
            done = each()
            if inspect.isawaitable(done):
                await within(done)
        value = probe()
        if inspect.isawaitable(value):
            value = await within(value)
        if value:
            return cast(T, value)
        if loop.time() >= end:
            _fail(what, timeout, value, show)
        await asyncio.sleep(interval)
