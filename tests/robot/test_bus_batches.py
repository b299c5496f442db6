"""The virtual robot's topic bus wakes its node's loop once per batch, not once per message.

Issue 25: every message a middleware thread handed to the loop with ``call_soon_threadsafe``
wrote one byte into the loop's self-pipe, the pipe asyncio's signal handling shares; a flood
while the loop was held up filled it and SIGTERM was lost. ``emulator.robot.bus.Bus`` (and
``ros_bus.RosBus``, through the same ``inbox_for``) now hands messages over through the
batching inbox. Two real Zenoh peers: one floods, the other's loop is held up meanwhile; the
calls of ``call_soon_threadsafe`` are counted on the real loop.
"""

from __future__ import annotations

import asyncio
import threading
import time
from typing import Any

from emulator.robot.bus import Bus
from tests.ports import zenoh_endpoint

FLOOD = 300
DEADLINE_S = 60.0  # generous: a busy machine delivers late; only a broken bus takes this long


async def _until(cond: Any, what: str) -> None:
    end = time.monotonic() + DEADLINE_S
    while not cond():
        assert time.monotonic() < end, f"not within {DEADLINE_S:g} s: {what}"
        await asyncio.sleep(0.02)


def test_a_flood_during_a_stall_wakes_the_loop_a_few_times_and_loses_nothing() -> None:
    async def main() -> tuple[int, list[int]]:
        loop = asyncio.get_running_loop()
        calls = [0]
        real = loop.call_soon_threadsafe

        def counting(*args: Any, **kw: Any) -> Any:
            calls[0] += 1
            return real(*args, **kw)

        endpoint = zenoh_endpoint()
        here = Bus(connect="tcp/127.0.0.1:1", listen=endpoint)
        there = Bus(connect=endpoint)
        got: list[int] = []
        try:
            loop.call_soon_threadsafe = counting  # type: ignore[method-assign]
            here.subscribe("/flood", lambda _t, v: got.append(int(v.get("n", -1))))
            # the peers find each other: publish until one message arrives
            await _until(lambda: (there.publish("/flood", {"n": -1}) or got), "a first message")
            await asyncio.sleep(0.2)  # late copies of the greeting drain (not asserted on)
            got.clear()
            calls[0] = 0

            def flood() -> None:
                for n in range(FLOOD):
                    there.publish("/flood", {"n": n})

            sender = threading.Thread(target=flood)
            sender.start()
            sender.join(DEADLINE_S)
            time.sleep(1.0)  # the loop held up while the messages arrive (a stalled node)
            await _until(lambda: FLOOD - 1 in got, "the whole flood delivered")
            return calls[0], [n for n in got if n >= 0]
        finally:
            loop.call_soon_threadsafe = real  # type: ignore[method-assign]
            there.close()
            here.close()

    wakeups, got = asyncio.run(main())
    assert got == list(range(FLOOD))  # in order, none lost
    assert wakeups < FLOOD // 10, f"{wakeups} wakeups for {FLOOD} messages"
