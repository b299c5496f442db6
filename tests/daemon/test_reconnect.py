"""The daemon waits between board clients as the one reconnect policy says.

In process, on the loop's simulated clock (``looptime``): a ``Daemon`` built from the TEDUSAR
robot whose board URL names an in-memory board that hangs up on every link. The daemon's board
task makes a new client after each failure; the loop times of the attempts (as the board side
sees them) are spaced exactly by the waits ``host.board.backoff.Backoff`` draws, with the
daemon's first wait and cap: jittered within [½, 1] of a nominal wait doubling up to the cap,
not the fixed doubling the daemon had before. When the board answers again the daemon connects,
and the policy is reset (its next failure waits from the first wait again).
"""

from __future__ import annotations

import asyncio
import contextlib
import itertools
import random
from pathlib import Path

import pytest

from host.board.backoff import Backoff
from host.daemon.core import RECONNECT_CAP_S, RECONNECT_FIRST_S, Daemon, DaemonOptions
from host.transports import memory
from tests.daemon.runner import TEDUSAR
from tests.host.memboard import MemoryBoard, tedusar

pytestmark = pytest.mark.looptime

ATTEMPTS = 10  # enough to reach the cap (0.2 · 2⁵ > 5)


async def test_the_daemons_reconnect_waits_come_from_the_shared_jittered_policy(
        tmp_path: Path) -> None:
    loop = asyncio.get_running_loop()
    name = "daemon-reconnect"
    tried: list[float] = []

    def hang_up(end: memory.MemoryEnd) -> None:  # a board that is there but never greets
        tried.append(loop.time())
        end.close()

    daemon = Daemon(DaemonOptions(system_dir=TEDUSAR, board_url=f"memory://{name}",
                                  journal=tmp_path / "journal.sqlite"), clock=loop.time)
    assert isinstance(daemon.reconnect, Backoff)
    assert (daemon.reconnect.first_s, daemon.reconnect.cap_s) == (RECONNECT_FIRST_S,
                                                                 RECONNECT_CAP_S)
    seed = 23
    daemon.reconnect.rng = random.Random(seed)
    stop = memory.listen(name, hang_up)
    task = asyncio.ensure_future(daemon._board_task())
    try:
        end = loop.time() + 600.0
        while len(tried) < ATTEMPTS + 1:
            assert loop.time() < end, tried
            await asyncio.sleep(0.05)
        policy = Backoff(RECONNECT_FIRST_S, RECONNECT_CAP_S, rng=random.Random(seed))
        waits = [policy.next() for _ in range(ATTEMPTS)]
        gaps = [b - a for a, b in itertools.pairwise(tried[:ATTEMPTS + 1])]
        assert gaps == pytest.approx(waits, abs=1e-3)
        nominal = [min(RECONNECT_FIRST_S * 2 ** i, RECONNECT_CAP_S) for i in range(ATTEMPTS)]
        assert all(n / 2 - 1e-3 <= g <= n + 1e-3 for g, n in zip(gaps, nominal, strict=True))
        assert any(g < n * 0.95 for g, n in zip(gaps, nominal, strict=True))  # jittered
        assert not daemon.link_up
        stop()
        async with MemoryBoard(tedusar(), name):  # the board answers: a good connection
            end = loop.time() + 120.0
            while not daemon.link_up:
                assert loop.time() < end, "the daemon never connected"
                await asyncio.sleep(0.05)
            assert daemon.reconnect.attempts == 0
            assert daemon.reconnect.nominal_s == RECONNECT_FIRST_S
    finally:
        stop()
        task.cancel()
        with contextlib.suppress(asyncio.CancelledError):
            await task
        daemon.diagnosis.close()
