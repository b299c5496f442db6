"""The watchdog supervisor: feed the hardware watchdog only while every task is alive.

Each task (the protection loop, each front end) is registered with the longest silence it may
keep, and calls ``beat(task, now)`` whenever it makes progress. ``check(now)`` feeds the
hardware watchdog through the HAL only if every task has beaten within its limit; otherwise it
stops feeding, records the first stale task in ``stale`` (for the next boot's report) and the
watchdog resets the board. A task that is legitimately idle beats anyway (front ends beat from
their accept/read loops with a timeout), so silence means hung, not idle.
"""


if False:  # typing only; MicroPython never imports typing (the block is compiled away)
    from firmware.hal import Hal


class Supervisor:
    def __init__(self, hal: "Hal") -> None:
        self.hal = hal
        self.names: "list[str]" = []
        self.limits: "list[int]" = []
        self.last: "list[int]" = []
        self.stale = ""

    def register(self, name: str, max_silence_ms: int, now: int) -> int:
        """Add a task; returns its id for ``beat``."""
        self.names.append(name)
        self.limits.append(max_silence_ms)
        self.last.append(now)
        return len(self.names) - 1

    def beat(self, task: int, now: int) -> None:
        self.last[task] = now

    def check(self, now: int) -> bool:
        last = self.last
        limits = self.limits
        for i in range(len(last)):
            if now - last[i] > limits[i]:
                if not self.stale:
                    self.stale = self.names[i]
                return False
        self.hal.wdt_feed()
        return True
