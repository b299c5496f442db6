"""``host.launch.waiting``: a deadline holds even when the step it waits through never returns.

Proof run G (stop 35's code, beside a CPU hog): a test waited for Modbus readings with
``each`` taking the next item of a stream; the stream went quiet and the test hung until
pytest-timeout killed it 600 s later, telling nothing of what it had seen. ``each`` and an
awaited ``probe`` now run within what is left of the deadline, and a missed one fails naming
what was awaited. These run on looptime's simulated clock: nothing waits in real time.
"""

from __future__ import annotations

import asyncio

import pytest

from host.launch.waiting import wait_until_async


@pytest.mark.looptime
async def test_an_each_that_never_returns_fails_at_the_deadline() -> None:
    seen: list[int] = []

    async def take() -> None:
        if len(seen) == 3:
            await asyncio.Event().wait()  # the stream went quiet: never returns
        seen.append(len(seen))

    loop = asyncio.get_running_loop()
    start = loop.time()
    with pytest.raises(AssertionError, match="timed out after 120 s waiting for five items"):
        await wait_until_async(lambda: len(seen) >= 5, 120, "five items", interval=0,
                               each=take, show=lambda: seen)
    assert loop.time() - start == pytest.approx(120, abs=1)
    assert seen == [0, 1, 2]


@pytest.mark.looptime
async def test_an_awaited_probe_that_never_returns_fails_at_the_deadline() -> None:
    async def probe() -> bool:
        await asyncio.Event().wait()
        return True  # never reached

    with pytest.raises(AssertionError, match="timed out after 30 s waiting for the answer"):
        await wait_until_async(probe, 30, "the answer")


@pytest.mark.looptime
async def test_a_slow_each_within_the_deadline_is_waited_for() -> None:
    n: list[int] = []

    async def slow() -> None:
        await asyncio.sleep(10)
        n.append(1)

    assert await wait_until_async(lambda: len(n) >= 3, 60, "three", each=slow) is True
