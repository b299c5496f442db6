"""A child process for the signal tests and ``benchmarks/stops.py``: the daemon's topic delivery
flooded while its event loop is held up, then a real SIGINT.

``python -m benchmarks._rigs.flood_child ENDPOINT RATE STALL_S [--asyncio]`` opens the daemon's real
topic source (``ZenohSource`` listening on ENDPOINT), a zenoh publisher (a second session, on a
thread) that sends RATE messages a second to it, and hears SIGINT/SIGTERM the way ``dxboard
run`` does (``host.launch.signals.StopSignals``; on code from before issue 25, which has no such
module, or with ``--asyncio``, the baseline of ``benchmarks/stops.py``: asyncio's
``loop.add_signal_handler`` and one ``call_soon_threadsafe`` per message, as before). Once
messages arrive it prints ``stalling``, holds the loop up for STALL_S seconds (a blocking call
on the loop, as a slow diagnosis or a descheduled daemon does) and, three quarters into the
stall, sends itself SIGINT. It prints ``heard SIGINT after S s`` (from the signal to the loop
hearing it) and exits 0 when the loop is told, or ``LOST`` and exits 1 when nothing was heard
``HEARD_S`` after the stall; then a line of counters (``messages N wakeups W dropped D``).
"""

from __future__ import annotations

import asyncio
import os
import signal
import sys
import threading
import time

import zenoh

from host.observers.sources.zenoh_peer import ZenohSource, zenoh_config

HEARD_S = 12.0  # beyond the 10 s a stop may take


def _publish(endpoint: str, rate: float, stop: threading.Event) -> None:
    session = zenoh.open(zenoh_config(connect=[endpoint]))
    try:
        pub = session.declare_publisher("flood")
        period, due = 1.0 / rate, time.monotonic()
        while not stop.is_set():
            for _ in range(max(1, int(rate / 100))):  # in bursts: the rate, not the sleeps
                pub.put(b"x" * 16)
            due += period * max(1, int(rate / 100))
            time.sleep(max(0.0, due - time.monotonic()))
    finally:
        session.close()  # type: ignore[no-untyped-call]


async def _run(endpoint: str, rate: float, stall_s: float, old: bool) -> int:
    loop = asyncio.get_running_loop()
    heard = asyncio.Event()
    signals = None
    try:
        if not old:
            from host.launch.signals import StopSignals
            signals = StopSignals(loop, heard.set).install()
    except ImportError:
        old = True
    if old:  # before issue 25: asyncio's signal handling, on the shared self-pipe
        for sig in (signal.SIGINT, signal.SIGTERM):
            loop.add_signal_handler(sig, heard.set)
    source = ZenohSource(listen=[endpoint])
    if old:  # the delivery before issue 25 too: a wakeup byte per message
        source._post = lambda lp, cb, msg: lp.call_soon_threadsafe(cb, msg)  # type: ignore
    got = [0]
    source.subscribe("/flood", lambda m: got.__setitem__(0, got[0] + 1))
    stop = threading.Event()
    pub = threading.Thread(target=_publish, args=(endpoint, rate, stop), daemon=True)
    pub.start()
    try:
        while got[0] == 0:
            await asyncio.sleep(0.05)
        print("stalling", flush=True)
        threading.Timer(stall_s * 0.75, os.kill, (os.getpid(), signal.SIGINT)).start()
        t0 = time.monotonic()
        time.sleep(stall_s)  # the loop held up; messages pile up behind it
        try:
            await asyncio.wait_for(heard.wait(), HEARD_S)
            print(f"heard SIGINT after {time.monotonic() - t0 - stall_s * 0.75:.2f} s",
                  flush=True)
            code = 0
        except TimeoutError:
            print("LOST", flush=True)
            code = 1
    finally:
        stop.set()
        pub.join(5)
        inbox = getattr(source, "_inbox", None)
        print(f"messages {got[0]} wakeups {inbox.wakeups if inbox else -1} "
              f"dropped {source.dropped if inbox else -1}", flush=True)
        source.close()
        if signals is not None:
            signals.done()
            signals.close()
    return code


def main() -> int:
    endpoint, rate, stall_s = sys.argv[1], float(sys.argv[2]), float(sys.argv[3])
    return asyncio.run(_run(endpoint, rate, stall_s, "--asyncio" in sys.argv[4:]))


if __name__ == "__main__":
    sys.exit(main())
