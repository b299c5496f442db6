"""Four loops whose times on a Pico W and a Pico 2 W are published, counted here in
instructions: what one instruction of MicroPython costs on each MCU (board_cortexm.py).

The published table (github.com/shaoziyang/micropython_benchmarks, README, 2024) times the
same programs on some forty boards, the RP2040 under MicroPython v1.23.0 at 125 MHz among
them: nothing else on record times MicroPython's bytecode on an RP2040. Each loop below does
the work of one of its columns, with the same arguments, in the same shape (a function of one
list, called once), so that its bytecode is the same:

- ``add``: 100,000 small-integer additions of list items (the dispatch loop, nothing
  allocated);
- ``mul``: 100,000 products too big for a small integer (each a new long integer: the heap);
- ``fadd``: 100,000 float additions (each a new float);
- ``pi``: 1,000 digits of pi from the series t = t * n // d (long-integer arithmetic).

Prints ``LOOP name instructions`` per loop. Each count stays under 2**29, the instruction
clock's half period, so that one ``ticks_diff`` measures it.
"""

import gc
import time

import icount


def add(args):
    for _ in range(args[0]):
        r = args[1] + args[2]  # noqa: F841 (stored, as in the timed loop)


def mul(args):
    for _ in range(args[0]):
        r = args[1] * args[2]  # noqa: F841 (stored, as in the timed loop)


def pi(args):
    guard = 8
    one = 10 ** (args[0] + guard)
    t, c, n, na, d, da = 3 * one, 3 * one, 1, 0, 0, 24
    while t > 1:
        n, na, d, da = n + na, na + 8, d + da, da + 32
        t = t * n // d
        c += t
    return c // (10 ** guard)


LOOPS = (
    ("add", add, [100000, 12345678, 56781234]),
    ("mul", mul, [100000, 12345678, 56781234]),
    ("fadd", add, [100000, 12345678.1234, 56781234.5678]),
    ("pi", pi, [1000]),
)

for name, fn, args in LOOPS:
    gc.collect()
    start = icount.instructions()
    fn(args)
    print("LOOP", name, time.ticks_diff(icount.instructions(), start))
