"""The ``time`` the shipped HAL uses on a parts world run without the bench's clock.

``emulator.parts.bench`` puts ``emulator/parts/clock`` first on ``MICROPYPATH``, so that the
firmware's ``import time`` is the world's clock. The part tests and the tick benchmark build
the HAL themselves (``firmware.hal.target.build``) in an interpreter whose ``time`` is the
port's own (or CPython's), and hand it this instead (``target.time = BoardTime(world,
port_time)``): ``ticks_ms``/``ticks_diff`` are the port's, or under CPython, which has
neither, the world's clock; ``sleep_us`` is a busy wait of the microcontroller, charged to
the world's clock as the bench's ``time`` does, so that the parts see the time pass (a smart
switch's sense output settles within it).
"""

if False:  # typing only; MicroPython never imports typing (the block is compiled away)
    from typing import Any

    from emulator.parts.world import World


class BoardTime:
    def __init__(self, world: "World", port: "Any" = None) -> None:
        self.world = world
        # the port's ``time`` (MicroPython), unless it lacks ticks (CPython's)
        self.port = port if hasattr(port, "ticks_ms") else None

    def ticks_ms(self) -> int:
        if self.port is not None:
            return int(self.port.ticks_ms())
        return self.world.now_us // 1000

    def ticks_diff(self, a: int, b: int) -> int:
        if self.port is not None:
            return int(self.port.ticks_diff(a, b))
        return a - b

    def sleep_us(self, us: int) -> None:
        self.world.charge(int(us))
