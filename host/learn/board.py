"""The board's side of learning: each channel's current readings, and the probe (``--probe``).

``watch_board(client, rec, until)`` reads the channels' names and configurations (which are
protected) and collects every reading's currents (amperes, while a channel is on) into the
``Recording`` until the monotonic time ``until``. ``probe(client, rec, seen)`` then switches
each channel that is on and not protected off in turn, for at most ``OFF_S`` seconds (the
board's ``force`` flag is never given, so the board itself refuses a protected channel, should
its configuration change meanwhile), and notes which topics went silent and which nodes left
the graph (``seen``: the watcher's ``count`` and ``present``). The channel is switched on again
in a ``finally``: after an error, a refused switch, or Ctrl-C (the task's cancellation), every
channel the probe switched off is on again before the command ends.
"""

from __future__ import annotations

import asyncio
import logging
import time
from collections.abc import Callable
from typing import Any, Protocol

from host.learn.recording import ChannelSeen, Probe, Recording

log = logging.getLogger(__name__)

OFF_S = 1.5  # each channel off this long (the round trips keep it under 2 s)
SETTLE_S = 0.5  # messages already under way when the channel went off
ACTIVE_S = 2.0  # a topic with a message in the last this many seconds is live before a probe
RESTORE_TRIES = 3


class Seen(Protocol):
    def count(self, topic: str, since: float) -> int: ...

    def present(self) -> set[str]: ...


async def watch_board(client: Any, rec: Recording, until: float) -> None:
    """Channel names, protection and current readings until ``until`` (monotonic)."""
    names = await client.channel_names()
    for i, name in enumerate(names):
        cfg = await client.get_channel_config(i)
        rec.channels[i] = ChannelSeen(i, name, bool(cfg.get("protected", False)))
    readings: dict[int, list[float]] = {i: [] for i in range(len(names))}

    async def collect() -> None:
        from host.board.types import Reading

        async for item in client.subscribe(10):
            if isinstance(item, Reading):
                for i, ma in enumerate(item.currents_ma):
                    if item.on_mask >> i & 1 and i in readings:
                        readings[i].append(ma / 1000.0)

    task = asyncio.create_task(collect())
    try:
        await asyncio.sleep(max(0.0, until - time.monotonic()))
    finally:
        task.cancel()
        await asyncio.gather(task, return_exceptions=True)
    for i, cs in readings.items():
        ch = rec.channels[i]
        rec.channels[i] = ChannelSeen(i, ch.name, ch.protected, tuple(cs))


async def probe(client: Any, rec: Recording, seen: Seen,
                progress: Callable[[str], None]) -> list[int]:
    """Switch each unprotected channel that is on off in turn (see the module); the channels
    probed."""
    state = await client.state()
    done = []
    for ch in state.channels:
        c = rec.channels.get(ch.channel)
        if c is None or c.protected or not ch.commanded:
            continue
        now = time.monotonic()
        live = [t for t in rec.arrivals if seen.count(t, now - ACTIVE_S) > 0]
        before = seen.present()
        progress(f"probe: channel {ch.channel} ({c.name}) off for {OFF_S:g} s")
        off = time.monotonic()
        try:
            await client.switch(ch.channel, False)
            await asyncio.sleep(OFF_S)
            quiet = off + SETTLE_S
            stopped = tuple(t for t in live if seen.count(t, quiet) == 0)
            kept = tuple(t for t in live if t not in stopped)
            gone = tuple(sorted(before - seen.present()))
        finally:
            await _restore(client, ch.channel)
        rec.probes.append(Probe(ch.channel, off, time.monotonic(), stopped, kept, gone))
        done.append(ch.channel)
    return done


async def _restore(client: Any, channel: int) -> None:
    """Switch ``channel`` on again, retrying a few times; log when it cannot."""
    for attempt in range(RESTORE_TRIES):
        try:
            await client.switch(channel, True)
            return
        except Exception as exc:  # the board's error, a lost link: try again
            log.error("probe: switching channel %d on again failed (%s), try %d of %d",
                      channel, exc, attempt + 1, RESTORE_TRIES)
    log.error("probe: channel %d is still off: switch it on with `dxboard board URL on %d`",
              channel, channel)
