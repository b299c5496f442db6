"""The board's side of learning: each channel's current readings, and the probe (``--probe``).

``watch_board(client, rec, until)`` reads the channels' names and configurations (which are
protected) and collects every reading's currents (amperes, while a channel is on) into the
``Recording`` until the monotonic time ``until``. ``probe(client, rec, seen)`` then switches each
channel that is on and not protected off in turn, for at most ``OFF_S`` seconds (the board's
``force`` flag is never given, so the board itself refuses a protected channel, should its
configuration change meanwhile), and notes which topics went silent and which nodes left the graph
(``seen``: the watcher's ``count`` and ``present``); it then waits up to ``RECOVER_S`` for them to
come back, and a topic that did not (its driver does not reconnect after its device was off) is
noted and counts as live for no later probe. The channel is switched on again in a ``finally``:
after an error, a refused switch, or Ctrl-C (the task's cancellation), every channel the probe
switched off is on again before the command ends.
"""

from __future__ import annotations

import asyncio
import functools
import logging
import time
from collections.abc import Awaitable, Callable
from typing import Any, Protocol, TypeVar

from host.learn.recording import ChannelProbe, ChannelSeen, Recording

log = logging.getLogger(__name__)
T = TypeVar("T")

OFF_S = 1.5  # each channel off this long (the round trips keep it under 2 s)
SETTLE_S = 0.5  # messages already under way when the channel went off
ACTIVE_S = 2.0  # a topic with a message in the last this many seconds is live before a probe
RECOVER_S = 5.0  # after a channel is on again, its topics get this long to come back
RESTORE_TRIES = 10
RETRY_S = 1.0  # between tries of a request whose link was down (the client reconnects)
TRIES = 10


class Seen(Protocol):
    def count(self, topic: str, since: float) -> int: ...

    def present(self) -> set[str]: ...


async def watch_board(client: Any, rec: Recording, until: float) -> None:
    """Channel names, protection and current readings until ``until`` (monotonic)."""
    names = await client.channel_names()
    for i, name in enumerate(names):
        cfg = await client.configurator.get_channel_config(i)
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
    keep = asyncio.create_task(_keep_link(client))
    try:
        return await _probe(client, rec, seen, progress)
    finally:
        keep.cancel()
        await asyncio.gather(keep, return_exceptions=True)


async def _keep_link(client: Any) -> None:
    """Readings, discarded: the link's watchdog calls a board that sends nothing lost."""
    async for _ in client.subscribe(5):
        pass


async def _probe(client: Any, rec: Recording, seen: Seen,
                 progress: Callable[[str], None]) -> list[int]:
    state = await _retry(client.state)
    done: list[int] = []
    since = time.monotonic() - ACTIVE_S  # the watch's last seconds
    for ch in state.channels:
        c = rec.channels.get(ch.channel)
        if c is None or c.protected or not ch.commanded:
            continue
        # evidence of what is live: ACTIVE_S of messages, all after the last probe
        await asyncio.sleep(max(0.0, since + ACTIVE_S - time.monotonic()))
        live = [t for t in rec.arrivals if seen.count(t, since) > 0]
        before = seen.present()
        progress(f"probe: channel {ch.channel} ({c.name}) off for {OFF_S:g} s")
        off = time.monotonic()
        try:
            await _retry(functools.partial(client.switch, ch.channel, False))
            await asyncio.sleep(OFF_S)
            quiet = off + SETTLE_S
            stopped = tuple(t for t in live if seen.count(t, quiet) == 0)
            kept = tuple(t for t in live if t not in stopped)
            gone = tuple(sorted(before - seen.present()))
        finally:
            await _restore(client, ch.channel)
        on = time.monotonic()
        lost = await _recover(stopped, on, seen)
        if lost:
            progress(f"probe: {', '.join(lost)} did not come back within {RECOVER_S:g} s of "
                     f"channel {ch.channel} on again (a driver that does not reconnect)")
        rec.probes.append(ChannelProbe(ch.channel, off, on, stopped, kept, gone, lost))
        done.append(ch.channel)
        since = on  # a topic silent since (its driver did not come back) is not live
    return done


async def _recover(stopped: tuple[str, ...], on: float, seen: Seen) -> tuple[str, ...]:
    """Wait up to ``RECOVER_S`` for the stopped topics to come back; those that did not."""
    end = on + RECOVER_S
    while True:
        lost = tuple(t for t in stopped if seen.count(t, on) == 0)
        if not lost or time.monotonic() >= end:
            return lost
        await asyncio.sleep(0.1)


async def _retry(request: Callable[[], Awaitable[T]]) -> T:
    """``request()``, again after a lost link (a busy machine misses the board's frames for a
    second, the client reconnects by itself); the last error when every try failed."""
    from host.transports.errors import BoardUnreachable

    for _ in range(TRIES - 1):
        try:
            return await request()
        except BoardUnreachable as exc:
            log.warning("probe: %s; trying again", exc)
            await asyncio.sleep(RETRY_S)
    return await request()


async def _restore(client: Any, channel: int) -> None:
    """Switch ``channel`` on again, retrying a few times; log when it cannot."""
    for attempt in range(RESTORE_TRIES):
        try:
            await client.switch(channel, True)
            return
        except Exception as exc:  # the board's error, a lost link: try again
            log.error("probe: switching channel %d on again failed (%s), try %d of %d",
                      channel, exc, attempt + 1, RESTORE_TRIES)
            await asyncio.sleep(RETRY_S)
    log.error("probe: channel %d is still off: switch it on with `dxboard board URL on %d`",
              channel, channel)
