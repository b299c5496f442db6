"""The recorder loses no ``/board_stream`` item while it is held up (issue 28: a recorder never
misses a fault it was started before).

Two suites side by side at load 20+ once left a bag with two trips fewer than the daemon saw:
``/board_stream`` carries every item the daemon's hardware observer is fed, 100 a second, and
both its publisher and the recorder kept only the last 100 messages in DDS while the other end
lagged, so a recorder held up for a second lost board items. Here the daemon's own publisher
(``RosPublisher.board``) and the recorder's own source (``bagrun.recorder_source``) on a domain
of the test's; the recorder's executor thread is held up (the source's inbox locked, as a
loaded process leaves it unscheduled) while 3 s of the stream is published, then let go: every
item must arrive, in order. With depth 100 on either side this lost 200 of 300.
"""

from __future__ import annotations

import asyncio
import time

from host.board.types import LinkDown
from host.commands.bagrun import recorder_source
from host.observers.payload import TopicMessage
from host.ros import boardstream
from host.ros.publisher import RosPublisher
from tests.wait import wait_until_async

HELD = 300  # items published while the recorder is held up: 3 s of the board's 100 Hz
DEADLINE_S = 60.0  # generous: discovery and delivery on a busy machine


def _item(n: int) -> LinkDown:
    return LinkDown(host_time=float(n), reason=f"item {n}")


def test_a_recorder_held_up_loses_no_board_stream_item(domain: int) -> None:
    async def main() -> list[str]:
        got: list[str] = []

        def on(msg: TopicMessage) -> None:
            item = boardstream.decode(msg)  # type: ignore[arg-type]
            assert isinstance(item, LinkDown)
            got.append(item.reason)

        pub = RosPublisher(["lidar"], domain)
        source = recorder_source(domain, [(boardstream.TOPIC, boardstream.TYPE)], time.time)
        try:
            source.subscribe(boardstream.TOPIC, on)
            # matched: publish until one arrives
            await wait_until_async(lambda: got, DEADLINE_S, "a first board item",
                                   each=lambda: pub.board(_item(-1), 0.0))
            await asyncio.sleep(0.5)  # late copies of the greeting drain (not asserted on)
            inbox = source._inbox
            assert inbox is not None
            got.clear()
            with inbox._lock:  # the recorder's executor blocks on its next message
                for n in range(HELD):
                    pub.board(_item(n), float(n))
                    time.sleep(0.01)  # the board's 100 Hz
            await wait_until_async(lambda: f"item {HELD - 1}" in got, DEADLINE_S,
                                   "the last item held", show=lambda: got[-3:])
            return [r for r in got if r != "item -1"]
        finally:
            source.close()
            pub.close()

    got = asyncio.run(main())
    assert got == [f"item {n}" for n in range(HELD)], f"{HELD - len(got)} lost"
