"""No silence judged ahead of the messages still waiting in the daemon's own inbox.

The ROS 2 source takes each message on its executor's thread, stamps it when it came in, and
hands it to the loop through an inbox (``emulator.inbox``). A loop far behind its messages (a
daemon beside CPU hogs, a stranger flooding ``/odom``) drains that inbox in 50 ms slices, its
timers running in between: the observers' deadlines fired while seconds of messages waited, and
the frequency observer called ``/scan`` silent at its cap, which power-cycled a healthy Hokuyo
(issue 25, ``tests/ros/test_daemon_spoof.py``: messages read 4 s after they came in). Here on
the loop's simulated clock: a ``/scan`` publisher at 40 Hz whose messages wait in the inbox
while the loop is busy elsewhere (``Held``), then are read one per turn of the loop (a slice
per message), timers in between. Nothing is silent, its word is refreshed on time meanwhile,
and a real hang afterwards is still found at its limit.
"""

from __future__ import annotations

import asyncio
import contextlib
import logging

import pytest

import host.atoms as A
from host.diagnosis.observations import Observation
from host.observers import FrequencyObserver, ObserverHub, TopicMessage, Update
from host.observers.silence import JITTER_S, STARVED_CAP_S, ChainState
from host.observers.sources.base import Callback, Subscription, TopicSource
from host.observers.sources.inbox import Inbox
from host.observers.topics import DEFAULT_SILENCE, JITTER_FLOOR_S

pytestmark = pytest.mark.looptime

TOPIC = "/scan"
RATE = 40.0  # the Hokuyo's, as system.yaml observes it
WINDOW = 0.5
LIMIT = DEFAULT_SILENCE / RATE  # 0.1 s
HELD_S = 3.0  # past the bound without a probe (0.6 s) and the starved cap (2.1 s)

Item = tuple[Callback, TopicMessage]


class Held(Inbox[Item]):
    """The source's inbox on a loop busy elsewhere: while ``held``, what comes in waits (the
    loop gets to no drain); ``release`` lets the loop read it."""

    held = False

    def put(self, item: Item) -> None:
        if not self.held:
            super().put(item)
            return
        with self._lock:
            self._items.append(item)
            self._scheduled = True  # the drain the loop has not got to yet

    def release(self) -> None:
        self.held = False
        self.loop.call_soon(self._drain)


class _Sub(Subscription):
    def close(self) -> None:
        pass


class Source(TopicSource):
    """A middleware source: ``came_in`` is its thread taking a message, at the loop's time."""

    def __init__(self, loop: asyncio.AbstractEventLoop) -> None:
        super().__init__(clock=loop.time)
        self.loop = loop
        self.callbacks: dict[str, Callback] = {}
        self.last = float("nan")  # when the last message came in
        self._inbox = self.inbox = Held(loop, lambda item: item[0](item[1]), name="test")

    def subscribe(self, topic: str, callback: Callback) -> Subscription:
        self.callbacks[topic] = callback
        return _Sub()

    def came_in(self, topic: str) -> None:
        self.last = self.clock()
        self._post(self.loop, self.callbacks[topic], TopicMessage(self.last, topic, b""))


class Starved:
    """The publisher chain (and the daemon in it) waiting for a CPU all along: every gap is
    excused, up to the cap."""

    def __init__(self, loop: asyncio.AbstractEventLoop) -> None:
        self.loop = loop
        self.t0 = loop.time()

    def read(self) -> ChainState | None:
        return ChainState(self.loop.time() - self.t0, 1)


def verdicts(said: list[Update]) -> list[tuple[bool, float]]:
    """The changes of ``ok(/scan)`` (refreshes left out), with their times."""
    out: list[tuple[bool, float]] = []
    for u in said:
        if isinstance(u, Observation) and u.literal.atom == str(A.ok(TOPIC)) \
                and (not out or out[-1][0] != u.literal.positive):
            out.append((u.literal.positive, u.time))
    return out


@pytest.mark.parametrize("starved", [False, True], ids=["bound", "starved-cap"])
async def test_a_topic_is_not_silent_while_its_messages_wait_in_the_inbox(
        starved: bool, monkeypatch: pytest.MonkeyPatch, caplog: pytest.LogCaptureFixture
        ) -> None:
    monkeypatch.setattr("emulator.inbox.SLICE_S", 0.0)  # a loop so far behind: one per turn
    loop = asyncio.get_running_loop()
    obs = FrequencyObserver(TOPIC, rate=RATE, tolerance=10, window=WINDOW)
    if starved:
        obs.probe = Starved(loop)
    said: list[Update] = []
    hub = ObserverHub([obs], said.extend, clock=loop.time)
    source = Source(loop)
    await hub.start(source)
    running = True

    async def publish() -> None:
        while running:
            source.came_in(TOPIC)
            await asyncio.sleep(1 / RATE)

    task = asyncio.create_task(publish())
    try:
        await asyncio.sleep(1.0)
        assert verdicts(said) == [(True, pytest.approx(loop.time(), abs=1.0))]
        source.inbox.held = True
        held_at = loop.time()
        with caplog.at_level(logging.WARNING, "host.observers.hub"):
            await asyncio.sleep(HELD_S)  # the observer's deadlines come and go meanwhile
            waiting = source.waiting_since()
            assert waiting is not None and waiting < held_at + 1 / RATE
            source.inbox.release()
            while source.waiting_since() is not None:
                await asyncio.sleep(0.001)
        await asyncio.sleep(1.0)
        assert [ok for ok, _ in verdicts(said)] == [True]  # never silent: only unread
        assert any("after they came in" in r.getMessage() for r in caplog.records)
        # meanwhile its word was refreshed on time (not as of the messages read): the
        # diagnosis does not lose the literal to its validity while the daemon catches up
        refreshed = [u.time for u in said if isinstance(u, Observation)
                     and held_at + 1.0 < u.time < held_at + HELD_S]
        assert refreshed, [u.time for u in said]
    finally:
        running = False
        with contextlib.suppress(asyncio.CancelledError):
            await task
    # a real hang afterwards: found at its limit (the starved chain: at the cap), as before
    last = source.last
    deadline = last + LIMIT + (STARVED_CAP_S if starved else WINDOW) + 0.1
    while [ok for ok, _ in verdicts(said)] == [True]:
        assert loop.time() < deadline
        await asyncio.sleep(0.005)
    silent_at = verdicts(said)[-1][1]
    if starved:
        assert silent_at == pytest.approx(last + LIMIT + STARVED_CAP_S, abs=0.03)
    else:
        assert silent_at <= last + LIMIT + 2 * JITTER_FLOOR_S + 2 * JITTER_S + 0.01
    await hub.close()
