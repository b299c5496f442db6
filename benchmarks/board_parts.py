"""The board firmware's tick on register-level models of the real chips, per board revision.

``python -m benchmarks.board_firmware --parts`` runs this (``--write`` puts its section in
RESULTS.md). For every revision in ``firmware/boards`` whose sense chip has a model wiring
(``emulator.parts.wiring``), a MicroPython child (``micropython benchmarks/board_parts.py
REV``, with ``emulator/parts`` on ``MICROPYPATH`` so that ``import machine`` is the parts'
model) wires a parts world as that board, builds the shipped HAL
(``firmware/hal/target.build``: its chip driver checks IDs and configures every chip) and the
protection (``firmware.board.Board``), boots it, and runs ``PARTS_TICKS`` ticks of 10 ms with
every channel on. Per tick it measures:

- the firmware's CPU: the tick's wall time minus the time inside the parts' ``machine`` calls
  (C on the board, where an I2C call blocks for its bus time; here they run the models);
- the sensing time: the I2C bus's, from the simulated clock the bus charges at the revision's
  frequency; on a board without I2C (rev C), what the ADC's conversions charged the clock;
- right after the tick, ``reference()``, a fixed piece of pure Python of the same kind (method
  calls, attributes, integers, lists): the tick as a ratio of it is a figure the machine's load
  does not move (both slow down alike), and it carries to any MicroPython: on a Pico,
  ``reference_us()`` times it, and tick = ratio x that;

and the heap that HAL and board hold after boot. The parent turns that into a Markdown section.
"""

import os
import sys

# the checkout before benchmarks/ (no pathlib on MicroPython, which runs it from the checkout)
ROOT = __file__.rsplit("/", 2)[0] if __file__.count("/") >= 2 else "."
sys.path.insert(0, ROOT)

# 30 s of board time: every chip's CONFIG checked 300 times (DXBOARD_PARTS_TICKS: fewer, to
# try; a Pico's os has no getenv)
PARTS_TICKS = int(getattr(os, "getenv", lambda name: None)("DXBOARD_PARTS_TICKS") or 3000)
REF_LOOPS = 150  # reference(): about as much Python as one tick, on the unix port


class _Ref:
    def __init__(self):
        self.v = 0
        self.hist = [0] * 8

    def step(self, x):
        v = (self.v + x * 3) & 0xFFFF
        if v > 40000:
            v -= 1000
        self.hist[x & 7] = v
        self.v = v
        return v


def reference(n=REF_LOOPS):
    """A fixed piece of pure Python: a method call, attribute reads and writes, integer
    arithmetic, a comparison and a list store, ``n`` times."""
    r = _Ref()
    total = 0
    for i in range(n):
        total += r.step(i)
    return total


def reference_us(runs=200):
    """The fastest of ``runs`` timings of ``reference()``, in us (run this on a Pico)."""
    import time

    best = None
    for _ in range(runs):
        t = time.ticks_us()
        reference()
        d = time.ticks_diff(time.ticks_us(), t)
        best = d if best is None or d < best else best
    return best


# the calls into the parts' ``machine`` that are C on the board (an I2C call blocking for its
# bus time): their time here is the models', not the firmware's CPU
MACHINE_CALLS = (("I2C", ("readfrom_mem_into", "readfrom_mem", "writeto_mem", "readfrom",
                          "readfrom_into", "writeto", "scan")),
                 ("Pin", ("value",)), ("ADC", ("read_u16",)), ("WDT", ("feed",)),
                 ("mem32", ("__getitem__",)))  # (an instance: its class's)
# and MicroPython's ``time.sleep_us`` (C on the board too; a busy wait): ``BoardTime``'s here


def _timer(spent, clock, diff):
    """The wrapper ``time_machine`` puts around each call: ``spent[0]`` sums the time inside
    the outermost calls, ``spent[2]`` counts them."""
    def timed(fn):
        def call(*args):  # the HAL calls these positionally; no dict to allocate per call
            if spent[1]:
                return fn(*args)
            spent[1] = 1
            spent[2] += 1
            t = clock()
            try:
                return fn(*args)
            finally:
                spent[0] += diff(clock(), t)
                spent[1] = 0
        return call
    return timed


def time_machine(machine, clock, diff, bank=None, meter=None):
    """Wrap the parts' ``machine`` classes so that ``spent[0]`` sums the time inside their
    calls (the outermost only: a call inside another is not counted twice), whatever HAL
    object makes them; ``spent[2]`` counts those calls (see ``layer_ns``). ``bank``: the HAL's
    sensing driver, whose ``sleep_us`` (MicroPython's, handed to it at build) is wrapped too.
    ``meter``: the bare Cortex-M board's ``icount`` module, whose ``timed`` wraps in C (it
    counts into ``meter.inside()`` and ``meter.calls()``, and ``spent`` stays unused)."""
    spent = [0, 0, 0]
    timed = meter.timed if meter is not None else _timer(spent, clock, diff)
    for cls_name, names in MACHINE_CALLS:
        cls = getattr(machine, cls_name)
        if not isinstance(cls, type):
            cls = type(cls)
        for name in names:
            setattr(cls, name, timed(getattr(cls, name)))
    if bank is not None and hasattr(bank, "sleep_us"):
        bank.sleep_us = timed(bank.sleep_us)
    return spent


def meter_layer(meter, clock, diff, n=200):
    """``layer_ns`` for the C wrapper of the bare Cortex-M board (instructions x 1000 a call):
    a wrapped C function's cost outside ``meter.inside()`` less calling it directly. It comes
    out negative: the C call's own dispatch falls inside the count, and belongs to the
    firmware (a board pays it calling its C ``machine``), so the net figure adds it back.
    Instruction counts do not vary: one loop of each suffices. Both call a local (a global
    ``abs`` is a miss in this module's globals first, which no ``machine`` call pays)."""
    fn = abs
    wrapped = meter.timed(fn)
    meter.inside()
    t = clock()
    for _ in range(n):
        wrapped(0)
    total = diff(clock(), t) - meter.inside()
    t = clock()
    for _ in range(n):
        fn(0)
    direct = diff(clock(), t)
    return (total - direct) * 1000 // n


def layer_ns(clock, diff, n=2000, runs=7):
    """What the measuring wrapper itself costs a call beyond what ``spent[0]`` catches and a
    direct call of the same C function, in ns: the fastest of ``runs`` wrapped loops less the
    fastest of ``runs`` direct ones (the load only adds to each). A tick's CPU less its calls x
    this is the firmware's own."""
    wrapped_best = direct_best = None
    for _ in range(runs):
        spent = [0, 0, 0]
        wrapped = _timer(spent, clock, diff)(abs)
        t = clock()
        for _ in range(n):
            wrapped(0)
        total = diff(clock(), t) - spent[0]
        t = clock()
        for _ in range(n):
            abs(0)
        direct = diff(clock(), t)
        wrapped_best = total if wrapped_best is None or total < wrapped_best else wrapped_best
        direct_best = direct if direct_best is None or direct < direct_best else direct_best
    got = (wrapped_best - direct_best) * 1000 // n
    return got if got > 0 else 0


class _Electrics:
    """The simulated electronics around the parts that ``emulator.parts.wiring`` asks for: a
    load of ``amps[ch]`` on each channel while its switch is closed, 24 V on the bus."""

    def __init__(self, closed, amps):
        self.closed = closed
        self.amps = amps

    def source(self, ch, ohm):
        closed, amps = self.closed, self.amps

        def fn(t):
            return (amps[ch] if closed[ch] else 0.0) * ohm, 24.0
        return fn

    def load(self, ch):
        amps = self.amps

        def fn(t):
            return amps[ch]
        return fn

    def drive(self, ch, level):
        self.closed[ch] = bool(level)


def parts_board(rev, before_build=None):
    """A parts world wired as revision ``rev`` (every file of ``firmware/boards``): a switch per
    enable pin read back on its status pin, a load per channel, the revision's sensing parts
    as ``emulator.parts.wiring`` wires them for every revision (a smart switch is its own
    switch: its IN replaces ours), 24 V at the divider; then the shipped HAL
    (``firmware/hal/target.build``) and the protection (``firmware.board.Board``) on it,
    booted, and the heap that HAL and board hold (``gc.mem_alloc`` after ``gc.collect``,
    modules already imported). None if no model of its sense chip is wired."""
    from emulator.parts import wiring
    from emulator.parts.world import World, install
    from firmware import boards

    board = boards.load(rev)
    if board["sense"].get("chip") not in wiring.WIRING:
        return None
    w = install(World())
    n = board["channels"]
    closed = [False] * n
    amps = [0.4 + 0.1 * ch for ch in range(n)]

    def wire(ch):
        def drive(level):
            closed[ch] = bool(level)

        w.wire_output(board["en_pins"][ch], drive)
        if board.get("status_pins"):
            w.wire_input(board["status_pins"][ch], lambda: closed[ch])

    for ch in range(n):
        wire(ch)
    wiring.wire(w, board, _Electrics(closed, amps))
    w.wire_adc(board["vin"]["adc_pin"], lambda: 24.0 / board["vin"]["divider"])
    import gc

    from firmware.board import Board
    from firmware.hal import target
    from firmware.hal.storage import MemStorage

    cfg = {"channels": [{"name": "c" + str(i), "rated_ma": 3000, "powerup": True}
                        for i in range(n)], "board": {"powerup_spacing_ms": 0}}
    from emulator.parts.boardtime import BoardTime

    # the port's ticks; a busy wait (a smart switch's settle) charged to the world's clock
    target.time = BoardTime(w, target._port_time)
    if before_build is not None:  # the meter on the parts' machine classes, before the HAL
        before_build()  # keeps any of their bound methods
    gc.collect()
    before = gc.mem_alloc()
    hal = target.build(board, MemStorage())
    b = Board(hal, cfg)
    b.boot(w.now_us // 1000)
    gc.collect()
    return w, board, hal, b, gc.mem_alloc() - before


def measure(rev):
    """Under MicroPython: the tick of revision ``rev`` on the parts; prints one PARTS line."""
    import time

    try:  # the bare Cortex-M board under QEMU (benchmarks/board_cortexm.py): instructions
        import icount as meter
        clock = meter.instructions
    except ImportError:
        meter = None
        clock = time.ticks_us
    diff = time.ticks_diff
    box = []

    def wrap():
        import machine  # the parts' (MICROPYPATH), the one the HAL is built with

        box.append(time_machine(machine, clock, diff, None, meter))

    got = parts_board(rev, wrap)
    if got is None:
        print("PARTS", rev, "none")
        return
    w, board, hal, b, heap = got
    spent = box[0]
    if hasattr(hal.ina, "sleep_us"):  # handed to the sensing driver at build
        hal.ina.sleep_us = meter.timed(hal.ina.sleep_us) if meter else _timer(
            spent, clock, diff)(hal.ina.sleep_us)
    i2c = board["sense"].get("i2c")
    bus = w.bus(i2c["id"]) if i2c else None

    def step():
        w.set_time(w.now_us + 10000 - w.now_us % 10000)
        spent[0] = 0  # per tick: a sum over the run would outgrow a small int in instructions
        calls = meter.calls() if meter else spent[2]
        if meter:
            meter.inside()
            meter.cold()  # the lookup cache as the part models left it would move the count
        t = clock()
        hal.wdt_feed()
        b.tick(w.now_us // 1000)
        took = diff(clock(), t)
        if meter:
            return took - meter.inside(), meter.calls() - calls
        return took - spent[0], spent[2] - calls

    for _ in range(200):  # 2 s: past the power-up and the inrush windows
        step()
    from protocol.constants import ST_ON

    on = sum(1 for ch in b.channels if ch.state == ST_ON)
    cpu, busy, refs, ratios, nets, owns = [], [], [], [], [], []
    layer = meter_layer(meter, clock, diff) if meter else layer_ns(clock, diff)
    for _ in range(PARTS_TICKS):
        # the time the sensing blocks the tick: the I2C bus's, or (no I2C) every conversion
        # and wait the simulated clock was charged with during the tick
        bus0 = bus.busy_us if bus else w.now_us + 10000 - w.now_us % 10000
        c, calls = step()
        busy.append((bus.busy_us if bus else w.now_us) - bus0)
        t = clock()
        reference()
        r = diff(clock(), t)
        cpu.append(c)
        refs.append(r)
        ratios.append(c * 1000 // max(r, 1))
        nets.append((c * 1000 - calls * layer) // max(r, 1))
        owns.append((c * 1000 - calls * layer) // 1000)
    cpu.sort()
    owns.sort()
    busy.sort()
    ratios.sort()
    nets.sort()
    print("PARTS", rev, board["channels"], on, cpu[0], cpu[len(cpu) // 2],
          cpu[int(len(cpu) * 0.95)], ratios[len(ratios) // 2],
          nets[len(nets) // 2], min(refs),
          sum(busy) // len(busy), busy[-1], heap, owns[len(owns) // 2])


#: what ``profile`` counts, a slot each
PROFILED = ("tick", "read_currents", "read_switches", "steady", "read_input_mv",
            "the sensing chips' viper read", "Channel.step", "reference()")


def profile(rev, ticks=500):
    """Under the bare Cortex-M board (``icount``): where the tick's instructions go, in the
    sections of ``PROFILED`` (each inclusive of what it calls, less the part models), summed
    over ``ticks`` ticks after 2 s; prints one PROFILE line a section (instructions a tick,
    calls a tick). The C wrappers that count add some 300 instructions a call to each
    section that contains one."""
    import time

    import icount
    import machine  # the parts' (MICROPYPATH)

    clock, diff = icount.instructions, time.ticks_diff
    got = parts_board(rev, lambda: time_machine(machine, clock, diff, None, icount))
    if got is None:
        print("PROFILE", rev, "none")
        return
    w, _board, hal, b, _heap = got
    if hasattr(hal.ina, "sleep_us"):
        hal.ina.sleep_us = icount.timed(hal.ina.sleep_us)
    import sys as _sys

    from firmware import board as fboard
    from firmware import channel as fchannel

    p = icount.profiled
    fboard.Board.tick = p(fboard.Board.tick, 0)
    refs = list(b.tick_refs)
    for at, slot in ((1, 1), (3, 2), (9, 4)):
        if refs[at] is not None:
            refs[at] = p(refs[at], slot)
    b.tick_refs = tuple(refs)
    fboard.steady = p(fboard.steady, 3)
    bank = _sys.modules[type(hal.ina).__module__]
    for name in ("ina226_read", "ina3221_read", "profet_read"):
        if hasattr(bank, name):
            setattr(bank, name, p(getattr(bank, name), 5))
    fchannel.Channel.step = p(fchannel.Channel.step, 6)
    ref = p(reference, 7)

    def step():
        w.set_time(w.now_us + 10000 - w.now_us % 10000)
        icount.cold()
        hal.wdt_feed()
        b.tick(w.now_us // 1000)

    for _ in range(200):
        step()
    icount.profile()
    for _ in range(ticks):
        step()
        ref()
    sums = icount.profile()
    for i, name in enumerate(PROFILED):
        print("PROFILE", rev, sums[i][0] // ticks, sums[i][1] // ticks, name)


def results(revs):
    """[(rev, fields or None)] from one MicroPython child per revision."""
    import subprocess

    out = []
    env = dict(os.environ, MICROPYPATH="emulator/parts:.:.frozen")
    for rev in revs:
        mp = subprocess.run([os.path.join(os.path.dirname(sys.executable), "micropython"),
                             "benchmarks/board_parts.py", rev],
                            capture_output=True, text=True, cwd=ROOT, env=env)
        line = [ln for ln in mp.stdout.splitlines() if ln.startswith("PARTS")]
        if not line:
            sys.exit("micropython parts run of " + rev + " failed: "
                     + (mp.stderr + mp.stdout).strip())
        fields = line[0].split()[2:]
        out.append((rev, None if fields == ["none"] else [int(x) for x in fields]))
    return out


def revisions():
    names = sorted(f for f in os.listdir(os.path.join(ROOT, "firmware", "boards"))
                   if f.startswith("rev_") and f.endswith(".py"))
    return ["rev-" + f[4:-3] for f in names]


def section(peak_memory):
    """The Markdown section: every revision's figures, the heap with 4 clients at 100 Hz
    (``peak_memory()``: benchmarks.board_firmware's), the load average of the run."""
    from benchmarks.mcu_speed import MEASURED as slow

    res = results(revisions())
    load = os.getloadavg()[0] if hasattr(os, "getloadavg") else float("nan")
    lines = [
        "## Board firmware on the parts (hwbench)",
        "",
        "`python -m benchmarks.board_firmware --parts --write` (or `python"
        " benchmarks/board_firmware.py --parts --write`; the measurement is"
        " `benchmarks/board_parts.py`): for every revision in `firmware/boards`, the shipped"
        " HAL (`firmware/hal/target.py` and its chip driver) and the protection (`Board.tick`)"
        " under the real MicroPython (unix port), against the register-level part models"
        " (`emulator/parts`) through the parts' `machine` module; I2C transactions charged to"
        f" the simulated clock at the revision's bus frequency. {PARTS_TICKS} ticks of 10 ms"
        " after 2 s of settling, every channel on. CPU is the tick's wall time on this machine"
        " minus the time inside the `machine` calls (I2C, Pin, ADC, WDT: C on the board, where"
        " an I2C call blocks for its bus time, counted separately; here they run the models)."
        " The layer that measures them costs something itself: 'with the layer' keeps it in"
        " (an upper bound, and the figure earlier runs gave); 'net' takes off each call's share"
        " of it, calibrated in the same run (`layer_ns`: the wrapper around a C function against"
        " calling it directly).",
        "",
        "The machine is loaded (2 cores, other engineers' work), which stretches every wall"
        " time. So each tick is also timed against `reference()`, a fixed piece of pure"
        " Python of the same kind run right after it: the median ratio tick/reference does not"
        " move with the load, and the uncontended tick is that ratio times the reference's"
        " fastest run. On a Pico, `reference_us()` (the same file) times the reference, and the"
        " tick there is the ratio times that: one number measured on a board replaces the"
        " published figures below.",
        "",
        f"Scaling to the boards' MCUs (benchmarks/mcu_speed.py): MicroPython's own benchmark"
        " suite (`tests/perf_bench`), run here under the same unix port and set against"
        " published runs of the same programs, puts MicroPython on an RP2350 (Pico 2 W, 150"
        f" MHz) {slow['rp2350']}x slower than this port (median of 7 programs), and an RP2040"
        f" (Pico W, 125 MHz) {slow['rp2040']}x (from the RP2350's figure and one program run on"
        " both boards; the pyboard's published figures give the same within 3 %). The column"
        " 'fits the 1 ms if' is the slowdown at which the tick would use all of its 1 ms CPU"
        " budget, so it stands whatever the true ratio is; a Pico's `reference_us()` replaces"
        " both with a measurement. This scaling is an estimate, kept because it needs no ARM"
        " tools: whether the goal is met is decided by the tick counted in each MCU's own"
        " instructions (`python -m benchmarks.board_cortexm`, in the dated sections below).",
        "",
        "| revision | channels on | CPU per tick (unix, with the layer): fastest / median /"
        " p95 | tick / reference (median), with the layer; net | net ratio x the reference's"
        f" fastest = the uncontended tick | on an RP2040 at {slow['rp2040']}x; on an RP2350 at"
        f" {slow['rp2350']}x (goal < 1 ms) | fits the 1 ms if the MCU is at most |"
        " sensing time per tick: the I2C bus's, or (no I2C) the ADC's conversions, mean / max"
        " (goal < 3 ms) | heap of HAL + board after boot |",
        "|---|---|---|---|---|---|---|---|---|",
    ]
    verdicts = []
    heaps = {}
    for rev, f in res:
        if f is None:
            lines.append(f"| {rev} | - | no part model wiring for its sense chip in"
                         " emulator/parts/wiring.py WIRING yet | - | - | - | - | - | - |")
            continue
        n, on, low, med, p95, gross, ratio, ref, bus_mean, bus_max, heap = f[:11]
        heaps[rev] = heap
        # the net ratio takes off the layer's calibrated cost per call times the tick's calls;
        # where that comes to (nearly) the whole tick (rev C's ~70 pin and ADC calls), the
        # calibration's error is larger than what is left: then the with-layer ratio, an
        # upper bound, is the figure
        net_ok = ratio * 10 > gross
        basis = ratio if net_ok else gross
        tick = basis * ref / 1000
        cpu_ms = tick * slow["rp2040"] / 1000
        cpu2_ms = tick * slow["rp2350"] / 1000
        net = f"{ratio / 1000:.2f}" if net_ok else "not measurable"
        which = "net ratio" if net_ok else "ratio with the layer (an upper bound)"
        lines.append(f"| {rev} | {on} of {n} | {low} / {med} / {p95} us"
                     f" | {gross / 1000:.2f}; {net}"
                     f" | {basis / 1000:.2f} x {ref} us = {tick:.0f} us"
                     + ("" if net_ok else " (with the layer)")
                     + f" | {cpu_ms:.1f} ms; {cpu2_ms:.1f} ms"
                     f" | {1000 / max(tick, 1):.0f}x slower"
                     f" | {bus_mean / 1000:.2f} / {bus_max / 1000:.2f} ms | {heap} B |")
        verdicts.append(
            f"{rev}: sensing time {'meets' if bus_max < 3000 else 'misses'} its goal"
            f" ({bus_max / 1000:.2f} ms against 3 ms); by the {which}, scaled, the CPU"
            f" estimate is {cpu_ms:.1f} ms on an RP2040 and {cpu2_ms:.1f} ms on an RP2350"
            " against the 1 ms goal (the count in Cortex-M instructions decides it);"
            " by that estimate the tick as a whole (CPU plus the I2C calls, or ADC"
            " conversions, which block on the board) takes"
            f" {cpu_ms + bus_max / 1000:.1f} ms of its 10 ms on an RP2040"
            f" and {cpu2_ms + bus_max / 1000:.1f} ms on an RP2350"
            + ("." if net_ok else "; its net figure is not measurable here: the measuring"
               " layer's calibrated cost per call, times the tick's many pin and ADC calls,"
               " comes to more than the tick."))
    lines += [""] + verdicts  # noqa: RUF005 (MicroPython parses this file: no [*x])
    idle_b, peak4_b, got4 = peak_memory()
    per_rev = [(rev,) + tuple(peak_memory(rev=rev))  # noqa: RUF005 (MicroPython parses this)
               for rev in sorted(heaps)]
    lines += ["", "The firmware's heap with 4 TCP clients subscribed at 100 Hz (goal < 64 KB:"
              " 65,536 B), under MicroPython, 5 s: on the emulated board (`App` on a remote HAL:"
              f" its objects beyond its imports) {peak4_b} B at its peak, {idle_b} B booted with"
              f" no client ({got4} frames per client); per revision, its shipped `main.py` on its"
              " part models counted from after its modules' import (the part models' `machine`"
              " objects, a few words of C each on a board, are Python objects here and count"
              " too: an upper bound), peak / booted with no client / fewest frames a client got: "
              + ", ".join(f"{r} {peak} / {idle} B / {got}" for r, idle, peak, got in per_rev)
              + ". Goal " + ("met" if all(p < 65536 for _, _, p, _ in per_rev) else "NOT met")
              + " on every revision.",
              "", f"Load average (1 min) at the run: {load:.2f}.", ""]
    return "\n".join(lines)


if __name__ == "__main__":
    if sys.implementation.name == "micropython":  # the child: one revision's figures
        if len(sys.argv) > 2 and sys.argv[2] == "profile":  # (the Cortex-M board only)
            profile(sys.argv[1])
        else:
            measure(sys.argv[1] if len(sys.argv) > 1 else "rev-a")
    else:  # run by hand under CPython: each revision through its MicroPython child
        import argparse

        argparse.ArgumentParser(
            description="The board firmware's tick on the part models, per revision, each in "
            "a MicroPython child; the section of RESULTS.md comes from "
            "python -m benchmarks.board_firmware --parts [--write].").parse_args()
        for rev, got in results(revisions()):
            print(rev, got)
