"""The ``time`` module for firmware on the bench: its ticks are the ``World``'s simulated clock.

``emulator.parts.bench`` puts this folder first on ``MICROPYPATH``, so that ``import time`` in
the shipped firmware and in MicroPython's own ``asyncio`` (its scheduler reads ``ticks_ms``)
gets this module: ``ticks_ms``/``ticks_us``/``ticks_cpu`` read ``world.current().now_us``,
which only the driver of the simulation moves (and the bus transactions and conversions the
firmware makes, each charging its duration), so the firmware's timers fire in lock-step with
the emulator's electronics. ``sleep``/``sleep_ms``/``sleep_us`` are a busy wait of the
microcontroller: they charge their time to that clock. ``ticks_diff``, ``ticks_add`` and the
calendar functions (``time``, ``localtime``, ``gmtime``, ``mktime``) are the port's own.
"""

import utime  # type: ignore[import-not-found]  # the port's built-in ``time``

from emulator.parts import world as _world

ticks_diff = utime.ticks_diff
ticks_add = utime.ticks_add
localtime = utime.localtime
gmtime = utime.gmtime
mktime = utime.mktime


def time() -> int:
    return utime.time()  # type: ignore[no-any-return]


def time_ns() -> int:
    return utime.time_ns()  # type: ignore[no-any-return]


def ticks_us() -> int:
    return _world.current().now_us


def ticks_ms() -> int:
    return _world.current().now_us // 1000


def ticks_cpu() -> int:
    return _world.current().now_us


def sleep_us(us: int) -> None:
    _world.current().charge(int(us))


def sleep_ms(ms: int) -> None:
    _world.current().charge(int(ms) * 1000)


def sleep(s: float) -> None:
    _world.current().charge(int(s * 1000000))
