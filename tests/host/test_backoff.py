"""The one reconnect policy (``host.board.backoff.Backoff``) and the board link's use of it.

The policy alone: each wait lies within [½, 1] of a nominal wait that doubles from ``first_s``
up to the cap, the waits really are spread (jittered, not the nominal one), ``reset()`` starts
again from ``first_s``, and nonsense parameters are refused. The link: on the loop's simulated
clock (``looptime``), the reopen attempts after a lost link are spaced exactly by the waits the
policy draws from the client's ``rng``, and a second loss after a good connection starts from
``backoff_s`` again. (The daemon's use of the same policy: ``tests/daemon/test_reconnect.py``.)
"""

from __future__ import annotations

import asyncio
import itertools
import random
from collections.abc import Callable

import pytest

from host.board import BoardClient, LinkDown, LinkUp
from host.board.backoff import Backoff
from host.transports import open_transport
from host.transports.base import Transport
from tests.host.memboard import KEY, MemoryBoard, tedusar


def nominals(first: float, cap: float, n: int) -> list[float]:
    return [min(first * 2 ** i, cap) for i in range(n)]


def test_each_wait_is_jittered_within_half_to_all_of_a_doubling_nominal() -> None:
    b = Backoff(0.1, 5.0, rng=random.Random(1))
    waits = [b.next() for _ in range(12)]
    for wait, nominal in zip(waits, nominals(0.1, 5.0, 12), strict=True):
        assert nominal / 2 <= wait <= nominal
    assert b.attempts == 12 and b.nominal_s == 5.0


def test_the_waits_are_spread_not_the_nominal_one() -> None:
    b = Backoff(5.0, 5.0, rng=random.Random(2))  # at the cap from the start
    waits = [b.next() for _ in range(400)]
    assert all(2.5 <= w <= 5.0 for w in waits)
    assert min(waits) < 2.75 and max(waits) > 4.75  # the whole band is used
    assert len({round(w, 6) for w in waits}) > 300  # not a handful of fixed values


def test_the_nominal_wait_stops_at_the_cap() -> None:
    b = Backoff(0.2, 5.0, jitter=0.0, rng=random.Random(3))
    assert [b.next() for _ in range(8)] == pytest.approx([0.2, 0.4, 0.8, 1.6, 3.2, 5.0, 5.0, 5.0])


def test_reset_after_a_good_connection_starts_from_the_first_wait() -> None:
    b = Backoff(0.2, 5.0, rng=random.Random(4))
    for _ in range(6):
        b.next()
    assert b.nominal_s == 5.0
    b.reset()
    assert b.attempts == 0 and b.nominal_s == 0.2
    assert 0.1 <= b.next() <= 0.2


def test_the_same_rng_gives_the_same_waits() -> None:
    a = Backoff(0.1, 2.0, rng=random.Random(5))
    b = Backoff(0.1, 2.0, rng=random.Random(5))
    assert [a.next() for _ in range(10)] == [b.next() for _ in range(10)]


@pytest.mark.parametrize(("first", "cap", "jitter"), [(0.0, 1.0, 0.5), (2.0, 1.0, 0.5),
                                                       (0.1, 1.0, 1.5), (0.1, 1.0, -0.1)])
def test_nonsense_parameters_are_refused(first: float, cap: float, jitter: float) -> None:
    with pytest.raises(ValueError, match="backoff"):
        Backoff(first, cap, jitter=jitter)


@pytest.mark.looptime
async def test_the_link_reopens_after_the_policys_waits_and_starts_afresh_after_a_good_link(
        ) -> None:
    loop = asyncio.get_running_loop()
    opened: list[float] = []  # loop times at which the link made a transport (an attempt)

    def factory(url: str, key: bytes | None) -> Transport:
        opened.append(loop.time())
        return open_transport(url, key)

    seed = 11
    c = BoardClient("memory://backoff", KEY, clock=loop.time, backoff_s=0.05, max_backoff_s=0.4,
                    rng=random.Random(seed), transport_factory=factory)
    items: list[tuple[float, object]] = []

    async def collect() -> None:
        async for item in c.subscribe(20):
            items.append((loop.time(), item))

    async def until(what: object, count: int) -> None:
        end = loop.time() + 60.0
        while sum(isinstance(x, what) for _, x in items) < count:  # type: ignore[arg-type]
            assert loop.time() < end, items[-3:]
            await asyncio.sleep(0.01)

    async def until_true(what: Callable[[], bool]) -> None:
        end = loop.time() + 60.0
        while not what():
            assert loop.time() < end, opened
            await asyncio.sleep(0.01)

    task: asyncio.Future[None] | None = None
    mb = MemoryBoard(tedusar(), "backoff")
    await mb.__aenter__()
    try:
        await c.connect()
        task = asyncio.ensure_future(collect())
        await asyncio.sleep(0.2)
        await mb.__aexit__()  # the board goes away: nothing listens
        await until(LinkDown, 1)
        lost_at = next(t for t, x in items if isinstance(x, LinkDown))
        await until_true(lambda: len(opened) >= 8)  # 1 connect + 7 failed attempts
        policy = Backoff(0.05, 0.4, rng=random.Random(seed))
        waits = [policy.next() for _ in range(7)]
        gaps = [b - a for a, b in itertools.pairwise([lost_at, *opened[1:8]])]
        assert gaps == pytest.approx(waits, abs=1e-3)  # the policy's waits, jitter and cap
        assert max(gaps) <= 0.4 + 1e-3
        mb = MemoryBoard(tedusar(), "backoff")  # the board is back
        await mb.__aenter__()
        await until(LinkUp, 1)
        attempts = len(opened)
        mb.drop_links()  # lost again after a good link
        await until(LinkDown, 2)
        await until_true(lambda: len(opened) > attempts)
        second_lost = [t for t, x in items if isinstance(x, LinkDown)][1]
        assert opened[attempts] - second_lost <= 0.05 + 1e-3  # from backoff_s, not the cap
    finally:
        if task is not None:
            task.cancel()
            await asyncio.wait([task])
        await c.close()
        await mb.__aexit__()
