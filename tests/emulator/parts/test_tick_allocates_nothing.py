"""The protection tick allocates nothing on the heap, on every revision's parts: the shipped
HAL (``firmware.hal.target``) and ``Board.tick``, ten channels on, under the real MicroPython
with its heap locked (``micropython.heap_lock``) for 50 ticks; the part models, which stand
for the chips and allocate freely, run with it unlocked. An allocation in the tick would raise
``MemoryError`` there, and on a board it would make the tick's cost depend on the heap's state
(``gc_alloc`` searching it) and bring on collections mid-tick. (A Python function's frame too
big for the stack is taken from the heap when it can be, and from the stack when the heap is
locked: that is MicroPython's own choice, not an allocation of the firmware's.)

Under pytest this runs the same check in a MicroPython child (``.venv/bin/micropython``):
CPython has no heap to lock. ``micropython tests/mpy_run.py tests/emulator/parts`` runs it
in place.
"""

import sys
import unittest

from firmware import boards

IS_MICROPYTHON = sys.implementation.name == "micropython"
_NO = object()  # an argument not given (the wrappers take a fixed number: no tuple)
LOCKED = [False]  # while the heap is locked around a tick


MP = []  # the micropython module (a global: a closure over it would take a cell more, and
# MicroPython calls a closure of more than five cells and arguments with a heap array)


def _unlocked(fn):
    """``fn`` called with the heap unlocked, locked again after (a part model's work)."""

    def call(self, a=_NO, b=_NO, c=_NO):
        locked = LOCKED[0]  # (a model's own machine calls, inside: already unlocked)
        if locked:
            LOCKED[0] = False
            MP[0].heap_unlock()
        try:
            if a is _NO:
                return fn(self)
            if b is _NO:
                return fn(self, a)
            if c is _NO:
                return fn(self, a, b)
            return fn(self, a, b, c)
        finally:
            if locked:
                MP[0].heap_lock()
                LOCKED[0] = True
    return call


class _Electrics:
    """0.5 A on each channel while its switch is closed, 24 V on the bus."""

    def __init__(self, closed):
        self.closed = closed

    def source(self, ch, ohm):
        closed = self.closed
        return lambda t: ((0.5 if closed[ch] else 0.0) * ohm, 24.0)

    def load(self, ch):
        return lambda t: 0.5

    def drive(self, ch, level):
        self.closed[ch] = bool(level)


def check(rev, ticks=50):
    """Under MicroPython: ``rev`` booted on its parts, 2 s of ticks, then ``ticks`` ticks with
    the heap locked; raises ``MemoryError`` (with where) if the firmware allocates."""
    import micropython

    MP[:] = [micropython]
    from emulator.parts import machine
    from emulator.parts.wiring import wire
    from emulator.parts.world import World, install
    from firmware.board import Board
    from firmware.hal.storage import MemStorage
    from tests.emulator.parts.test_machine import target_on

    # the models' calls, as the HAL makes them (classes wrapped before the HAL binds any)
    for cls, names in ((machine.I2C, ("readfrom_mem_into", "readfrom_mem", "writeto_mem")),
                       (machine.Pin, ("value",)), (machine.ADC, ("read_u16",)),
                       (machine.WDT, ("feed",)), (type(machine.mem32), ("__getitem__",))):
        for name in names:
            setattr(cls, name, _unlocked(getattr(cls, name)))
    board = boards.load(rev)
    n = board["channels"]
    w = install(World())
    closed = [False] * n

    def drive_of(ch):
        def drive(level):
            closed[ch] = bool(level)
        return drive

    for ch in range(n):
        w.wire_output(board["en_pins"][ch], drive_of(ch))
        if board.get("status_pins"):
            w.wire_input(board["status_pins"][ch], lambda ch=ch: closed[ch])
    wire(w, board, _Electrics(closed))
    w.wire_adc(board["vin"]["adc_pin"], lambda: 24.0 / board["vin"]["divider"])
    hal = target_on(w).build(board, MemStorage())
    if hasattr(hal.ina, "sleep_us"):  # a smart switch's settle: a busy wait on the world
        wait = hal.ina.sleep_us

        def sleep_us(us):
            locked = LOCKED[0]
            if locked:
                LOCKED[0] = False
                micropython.heap_unlock()
            try:
                wait(us)
            finally:
                if locked:
                    micropython.heap_lock()
                    LOCKED[0] = True
        hal.ina.sleep_us = sleep_us
    cfg = {"channels": [{"name": "c" + str(i), "rated_ma": 3000, "powerup": True}
                        for i in range(n)], "board": {"powerup_spacing_ms": 0}}
    b = Board(hal, cfg)
    b.boot(w.now_us // 1000)
    for _ in range(200):  # past the power-up and the inrush windows
        w.set_time(w.now_us + 10000 - w.now_us % 10000)
        hal.wdt_feed()
        b.tick(w.now_us // 1000)
    on = sum(1 for ch in b.channels if ch.physical)
    for _ in range(ticks):
        w.set_time(w.now_us + 10000 - w.now_us % 10000)
        micropython.heap_lock()
        LOCKED[0] = True
        try:
            hal.wdt_feed()
            b.tick(w.now_us // 1000)
        finally:
            LOCKED[0] = False
            micropython.heap_unlock()
    return on


def _revisions(root):
    import os

    return sorted("rev-" + f[4:-3] for f in os.listdir(root + "/firmware/boards")
                  if f.startswith("rev_") and f.endswith(".py"))


class TickAllocatesNothingTest(unittest.TestCase):
    def test_every_revision_ticks_with_the_heap_locked(self):
        if IS_MICROPYTHON:  # run from the checkout (tests/mpy_run.py)
            revs = _revisions(".")
            self.assertTrue(len(revs) >= 3)
            for rev in revs:
                self.assertEqual(check(rev), boards.load(rev)["channels"], rev)
            return
        import os
        import subprocess

        root = os.path.dirname(os.path.dirname(os.path.dirname(os.path.dirname(
            os.path.abspath(__file__)))))
        revs = _revisions(root)
        self.assertTrue(len(revs) >= 3)
        for rev in revs:
            code = ("import sys; sys.path.insert(0, '.'); sys.path.insert(0, 'tests/mpy'); "
                    "from tests.emulator.parts."
                    "test_tick_allocates_nothing import check; print('ON', check('" + rev
                    + "'))")
            env = dict(os.environ, MICROPYPATH="emulator/parts:.:.frozen")
            got = subprocess.run(
                [os.path.join(os.path.dirname(sys.executable), "micropython"), "-c", code],
                cwd=root, env=env, capture_output=True, text=True, timeout=600)
            self.assertEqual(got.returncode, 0, rev + ": " + got.stdout + got.stderr)
            self.assertIn("ON " + str(boards.load(rev)["channels"]), got.stdout)


if __name__ == "__main__":
    unittest.main()
