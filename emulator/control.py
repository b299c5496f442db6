"""The emulator's control endpoint: inject and clear faults at run time, read the truth.

Protocol: TCP, one JSON object per line (UTF-8, ``\\n``-terminated, at most 64 KiB) each way;
every request gets exactly one reply line, in order; the connection stays open for more.

    {"op": "hello"}
        -> {"ok": true, "board": "dxboard-emulator", "version": 1, "channels": [names],
            "faults": [fault names], "boot_ms": {name: ms until the device is ready}}
    {"op": "inject", "channel": "hokuyo" | 3 | "board", "fault": "hang",
     "params": {"permanent": "true"}}
        -> {"ok": true, "channel": 3, "fault": "hang", "params": {"permanent": true}}
    {"op": "clear"}                                   (every fault)
    {"op": "clear", "channel": C}                     (one channel's, or "board")
    {"op": "clear", "channel": C, "fault": NAME}      (one fault)
        -> {"ok": true, "cleared": N}
    {"op": "faults"}  -> {"ok": true, "faults": [{"channel", "fault", "params"}, ...]}
    {"op": "status"}  -> {"ok": true, "status": {...}}  (``Emulator.status``)

Parameter values may be strings (as typed on the command line) or JSON values; the emulator
converts and checks them (``emulator.faults``). Any error is ``{"ok": false, "error": "..."}``
with a message meant for a person; a bad line never closes the connection or touches the board.
The URL printed for this endpoint is ``control://HOST:PORT``.

``run_wallclock`` advances the emulator with the wall clock, ``CHUNK_MS`` at a time when it
catches up so that the front ends run in between (a host too busy to keep up for more than
``MAX_LAG_MS`` makes the simulated clock slip rather than starve them);
``Background`` runs it and the control server on an event loop in a thread (for ``dxboard
emulate`` and tests), and ``call`` runs a function on that loop so that nothing touches the
emulator from two threads.
"""

from __future__ import annotations

import asyncio
import contextlib
import threading
from collections.abc import Callable, Coroutine
from concurrent.futures import Future
from typing import Any, TypeVar

from emulator import faults as F
from emulator.jsonlines import MAX_LINE, Lines
from emulator.sim import Emulator

SCHEME = "control://"
CHUNK_MS = 50  # the most simulated time run_wallclock runs without yielding to the loop
MAX_LAG_MS = 2000  # how far the simulated clock may fall behind the wall clock and catch up
T = TypeVar("T")


def _hello(emu: Emulator) -> dict[str, Any]:
    return {"ok": True, "board": "dxboard-emulator", "version": 1,
            "channels": [c.name for c in emu.model.channels], "faults": list(F.FAULTS),
            "boot_ms": {c.name: c.boot_ms for c in emu.model.channels}}


def _inject(emu: Emulator, req: dict[str, Any]) -> dict[str, Any]:
    fault, params, channel = req.get("fault"), req.get("params", {}), req.get("channel")
    if not isinstance(fault, str) or not isinstance(params, dict) \
            or not isinstance(channel, str | int) or isinstance(channel, bool):
        raise F.FaultError("inject needs channel, fault and params {}")
    return {"ok": True, **emu.inject(channel, fault, params)}


def _clear(emu: Emulator, req: dict[str, Any]) -> dict[str, Any]:
    before = len(emu.active)
    channel, fault = req.get("channel"), req.get("fault")
    if channel is not None and (not isinstance(channel, str | int) or isinstance(channel, bool)):
        raise F.FaultError("channel must be a number or a name")
    if fault is not None and not isinstance(fault, str):
        raise F.FaultError("fault must be a name")
    emu.clear(channel, fault)
    return {"ok": True, "cleared": before - len(emu.active)}


def lines(emu: Emulator) -> Lines:
    """The control endpoint's requests (a ``FaultError`` is a refusal: a ``ValueError``)."""
    return Lines({
        "hello": lambda req, conn: _hello(emu),
        "inject": lambda req, conn: _inject(emu, req),
        "clear": lambda req, conn: _clear(emu, req),
        "faults": lambda req, conn: {"ok": True, "faults": emu.faults()},
        "status": lambda req, conn: {"ok": True, "status": emu.status()},
    }, max_line=MAX_LINE)


async def start_server(emu: Emulator, host: str = "127.0.0.1", port: int = 0) -> asyncio.Server:
    return await asyncio.start_server(lines(emu).serve, host, port, limit=MAX_LINE)


async def run_wallclock(emu: Emulator, stop: asyncio.Event, tick_ms: int = 10) -> None:
    """Advance the emulator's clock with the event loop's clock until ``stop`` is set (the
    wall clock on a real loop; a test's simulated clock on a simulated one)."""
    clock = asyncio.get_running_loop().time
    t0 = clock()
    start = emu.now
    while not stop.is_set():
        target = start + int((clock() - t0) * 1000)
        if target - emu.now > MAX_LAG_MS:  # a host too busy to keep up: the clock slips
            t0 += (target - emu.now - MAX_LAG_MS) / 1000
            target = emu.now + MAX_LAG_MS
        emu.advance_to(min(target, emu.now + CHUNK_MS))
        if emu.now < target:  # behind: catch up, letting the front ends and the stop in between
            await asyncio.sleep(0)
            continue
        with contextlib.suppress(TimeoutError):
            await asyncio.wait_for(stop.wait(), tick_ms / 1000)


class Background:
    """The emulator on the wall clock plus its control server, on a loop in a thread."""

    def __init__(self, emu: Emulator, host: str = "127.0.0.1", port: int = 0) -> None:
        self.emu = emu
        self.loop = asyncio.new_event_loop()
        self._stop: asyncio.Event | None = None
        self._ready = threading.Event()
        self.error: OSError | None = None
        self.address: tuple[str, int] = (host, port)
        self._thread = threading.Thread(target=self._run, daemon=True)

    @property
    def url(self) -> str:
        return f"{SCHEME}{self.address[0]}:{self.address[1]}"

    def _run(self) -> None:
        asyncio.set_event_loop(self.loop)
        self.loop.run_until_complete(self._main())

    async def _main(self) -> None:
        self._stop = asyncio.Event()
        try:
            server = await start_server(self.emu, *self.address)
        except OSError as exc:  # handed to start()
            self.error = exc
            self._ready.set()
            return
        self.address = server.sockets[0].getsockname()[:2]
        self._ready.set()
        async with server:
            await run_wallclock(self.emu, self._stop)

    def start(self) -> Background:
        self._thread.start()
        self._ready.wait(10)
        if self.error is not None:
            self._thread.join(10)
            raise self.error
        return self

    def call(self, fn: Callable[[], T]) -> T:
        """Run ``fn`` on the emulator's loop and return its result."""
        fut: Future[T] = Future()

        def run() -> None:
            try:
                fut.set_result(fn())
            except Exception as exc:  # handed to the caller's thread
                fut.set_exception(exc)

        self.loop.call_soon_threadsafe(run)
        return fut.result(10)

    def run(self, coro: Coroutine[Any, Any, T], timeout: float = 30) -> T:
        """Run a coroutine on the emulator's loop (front ends start this way)."""
        return asyncio.run_coroutine_threadsafe(coro, self.loop).result(timeout)

    def stop(self) -> None:
        if self._stop is not None:
            self.loop.call_soon_threadsafe(self._stop.set)
        self._thread.join(10)

    def __enter__(self) -> Background:
        return self.start()

    def __exit__(self, *exc: object) -> None:
        self.stop()
