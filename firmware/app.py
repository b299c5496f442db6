"""The firmware's non-blocking core: the board and its supervisor, one ``step`` at a time.

``App(hal)`` builds the ``Board`` and the ``Supervisor``; ``start()`` boots the board and
registers the protection task; ``step()`` reads the HAL clock, runs one protection tick, beats
the protection task, lets the supervisor feed the watchdog, and returns the time (ms) at which
the next step is due. The real board's loop (``firmware/main.py``) sleeps until then; the
emulator calls ``step`` on a simulated clock, as fast as it likes. Front ends, when they exist,
register their own tasks with ``supervisor`` and call ``board`` methods between steps.
"""

from firmware.board import Board
from firmware.supervisor import Supervisor
from protocol.compat import const

if False:  # typing only; MicroPython never imports typing (the block is compiled away)
    from firmware.config import Config
    from firmware.hal import Hal

PROTECT_SILENCE_MS = const(500)


class App:
    def __init__(self, hal: "Hal", factory: "Config | None" = None) -> None:
        self.hal = hal
        self.board = Board(hal, factory)
        self.supervisor = Supervisor(hal)
        self.protect_task = 0
        self.next_ms = 0

    def start(self) -> None:
        now = self.hal.ticks_ms()
        self.board.boot(now)
        self.protect_task = self.supervisor.register("protection", PROTECT_SILENCE_MS, now)
        self.supervisor.check(now)
        self.next_ms = now

    def step(self) -> int:
        now = self.hal.ticks_ms()
        self.board.tick(now)
        self.supervisor.beat(self.protect_task, now)
        self.supervisor.check(now)
        tick = self.board.cfg["board"]["tick_ms"]
        self.next_ms += tick
        if self.next_ms <= now:  # late (a slow step): do not try to catch up in a burst
            self.next_ms = now + tick
        return self.next_ms
