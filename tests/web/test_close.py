"""The web server's close ends even when its broadcaster swallows a cancellation.

Python 3.11's ``asyncio.wait_for`` returns the result instead of raising ``CancelledError``
when the awaited status arrives in the same loop pass as the cancellation; the broadcaster then
ran on, and ``close()`` (one ``cancel()`` and an ``await``) waited for it for ever: a daemon
whose status changed at the moment it was stopped never closed its page (issue 25, item 2).
The test stands in for that race with a broadcaster that swallows its first cancellation.
"""

from __future__ import annotations

import asyncio

from host.web import MemoryStatusSource, WebServer


async def test_close_ends_when_the_broadcaster_swallows_one_cancellation() -> None:
    web = WebServer(MemoryStatusSource(), push_interval_s=0.05, heartbeat_s=0.2)
    swallowed = asyncio.Event()

    async def stubborn() -> None:  # what wait_for's lost cancellation does to _broadcast
        while True:
            try:
                await asyncio.sleep(0.05)
            except asyncio.CancelledError:
                if swallowed.is_set():
                    raise
                swallowed.set()

    web._broadcast = stubborn  # type: ignore[method-assign]
    await web.start("127.0.0.1", 0)
    closing = asyncio.ensure_future(web.close())
    # a generous bound (it takes a tenth of a second); before the fix it waited for ever
    await asyncio.wait({closing}, timeout=60)
    done = closing.done()
    if not done:  # do not leave the server behind: a second cancellation ends the broadcaster
        closing.cancel()
        await asyncio.wait({closing}, timeout=10)
    assert done, "close() was still waiting for the broadcaster after 60 s"
    assert swallowed.is_set()
