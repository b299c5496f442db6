"""One learning session on a running robot: watch its topics and graph, read its board, probe.

``learn_live(options, progress)`` runs the ROS 2 watcher (``host.learn.live``), or with
``middleware="zenoh"`` the Zenoh one (``host.learn.zenoh_watch``: the robot's endpoint and
credentials file), for
``duration`` seconds while, with a board, it collects the channels' currents
(``host.learn.board``); then, with ``probe``, it switches each unprotected channel off in turn.
Progress lines (what it does, how far it is, how many topics and nodes so far) go to
``progress`` every ``PROGRESS_S`` seconds, since a learn takes a minute. ``check_written(dir)``
loads the written model as ``dxboard run`` will (system, observers, external) and returns its
problems: a learned model that does not load is a bug of the learner, never the user's.
"""

from __future__ import annotations

import asyncio
import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

from host.errors import UserError
from host.learn.recording import Recording

if TYPE_CHECKING:
    from host.learn.live import RosWatcher
    from host.learn.zenoh_watch import ZenohWatcher

PROGRESS_S = 10.0
JOIN_QUIET_S = 3.0  # the robot's publishers have all found the watcher when no new topic
JOIN_MAX_S = 30.0  # came for this long (or after this long at most)
CONNECT_S = 30.0  # the board's HELLO: generous, a robot's computer may be busy


@dataclass(frozen=True)
class LearnOptions:
    duration: float = 60.0
    board: str | None = None  # a board URL
    key: bytes | None = None
    probe: bool = False
    domain: int | None = None
    middleware: str = "ros2"  # or "zenoh"
    zenoh: tuple[str, ...] = ()  # the endpoints a Zenoh watcher connects to (default: the daemon's)
    auth: Path | None = None  # the daemon's Zenoh credentials file


def board_url(text: str) -> str:
    """``HOST:PORT`` as ``tcp://HOST:PORT``; a URL with a scheme as it is."""
    if "://" in text:
        return text
    host, _, port = text.rpartition(":")
    if not host or not port.isdigit():
        raise UserError(f"--board {text!r} is not HOST:PORT or a board URL",
                        "give e.g. --board 127.0.0.1:7000 or --board tcp://robot:7000")
    return f"tcp://{host}:{port}"


async def _progress(rec: Recording, until: float, say: Callable[[str], None]) -> None:
    while True:
        left = until - time.monotonic()
        if left <= 0:
            return
        await asyncio.sleep(min(PROGRESS_S, left))
        say(f"watching: {min(time.monotonic(), until) - rec.start:.0f} of "
            f"{until - rec.start:.0f} s, {len(rec.arrivals)} topics with messages, "
            f"{len(rec.nodes)} nodes")


async def _joined(watcher: RosWatcher | ZenohWatcher, say: Callable[[str], None],
                  network: str) -> None:
    """Wait until the robot's publishers have found the watcher (Zenoh's peers by gossip,
    ROS 2's by DDS discovery, one by one, seconds apart on a busy machine: a message on at
    least one topic and then no new topic for ``JOIN_QUIET_S``, at most ``JOIN_MAX_S``), then
    start the watch afresh, so that every topic is watched for the whole duration (on a
    loaded machine an 8 s ROS 2 watch ended without a message of the robot's camera)."""
    start = last = time.monotonic()
    seen: set[str] = set()
    while (time.monotonic() - last < JOIN_QUIET_S or not seen) \
            and time.monotonic() - start < JOIN_MAX_S:
        await asyncio.sleep(0.2)
        with watcher.lock:
            now = set(watcher.rec.arrivals)
        if now - seen:
            seen, last = now, time.monotonic()
    with watcher.lock:
        watcher.rec.arrivals.clear()
        watcher.rec.stamps.clear()
        watcher.rec.start = time.monotonic()
    say(f"joined the robot's {network}: {len(seen)} topics so far")


async def _learn(opts: LearnOptions, say: Callable[[str], None]) -> Recording:
    from host.learn.board import probe, watch_board

    watcher: RosWatcher | ZenohWatcher
    if opts.middleware == "zenoh":
        from host.learn.zenoh_watch import ZenohWatcher
        from host.observers.sources.zenoh_peer import DEFAULT_ENDPOINT

        rec = Recording(time.monotonic(), 0.0, source="the running robot (Zenoh)")
        watcher = ZenohWatcher(rec, opts.zenoh or (DEFAULT_ENDPOINT,), opts.auth)
        network = "zenoh network"
    else:
        from host.learn.live import RosWatcher

        rec = Recording(time.monotonic(), 0.0, source="the running robot (ROS 2)")
        watcher = RosWatcher(rec, opts.domain)
        network = "ROS 2 graph"
    try:
        await _joined(watcher, say, network)
    except BaseException:
        watcher.close()
        raise
    until = rec.start + opts.duration
    ticker = asyncio.create_task(_progress(rec, until, say))
    try:
        if opts.board is None:
            await asyncio.sleep(opts.duration)
        else:
            from host.board.client import BoardClient

            async with BoardClient(opts.board, opts.key, connect_timeout_s=CONNECT_S) as client:
                await watch_board(client, rec, until)
                if opts.probe:
                    say("probing: each unprotected channel off in turn, at most 2 s each")
                    probed = await probe(client, rec, watcher, say)
                    say(f"probed {len(probed)} channel(s), every one switched on again")
        rec.end = time.monotonic()
    finally:
        ticker.cancel()
        await asyncio.gather(ticker, return_exceptions=True)
        watcher.close()
    return rec


def learn_live(opts: LearnOptions, say: Callable[[str], None]) -> Recording:
    """Watch the running robot (see the module); the recording."""
    if opts.probe and opts.board is None:
        raise UserError("--probe needs the board", "give --board HOST:PORT")
    if opts.duration <= 0:
        raise UserError(f"--duration {opts.duration:g} is not a time",
                        "give seconds, e.g. --duration 60")
    say(f"watching the robot for {opts.duration:g} s"
        + (f" and its board {opts.board}" if opts.board else "")
        + (", then probing its channels" if opts.probe else "") + "; Ctrl-C stops it")
    return asyncio.run(_learn(opts, say))


def check_written(path: Path) -> list[str]:
    """The problems of the written model, loaded as ``dxboard run`` loads it."""
    from host.diagnosis.model import ModelError, check_system, load_system
    from host.observers.config import load_observers
    from host.repair.external import load_external

    problems = [str(p) for p in check_system(path)]
    if problems:
        return problems
    model = load_system(path)
    try:
        load_observers(path, model)
        load_external(path, model)
    except ModelError as exc:
        return [str(p) for p in exc.problems]
    return []
