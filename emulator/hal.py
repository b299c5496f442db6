"""The firmware's HAL on simulated electronics (see ``firmware/hal/__init__.py`` for the contract).

One ``SimHal`` exists per boot: its ``ticks_ms`` counts from that boot on the emulator's clock,
``reset_cause`` is the cause the emulator booted it with, ``wdt_feed`` records the time of the
feed (the emulator resets the board when the feeds stop for longer than the watchdog timeout),
and ``reboot`` asks the emulator for a soft reset. Storage survives resets: it belongs to the
emulated board, not to the boot.
"""

from __future__ import annotations

import os
from collections.abc import MutableSequence
from typing import Any, Protocol

from emulator.electronics import Electronics


class HalBoard(Protocol):
    """What a boot's HAL needs of the emulated board (``emulator.sim.Emulator`` is one)."""

    now: int
    electronics: Electronics
    storage: Any
    factory: Any  # the factory settings it was built with (None: none)
    last_feed: int
    reboot_requested: bool


class SimHal:
    def __init__(self, emu: HalBoard, cause: int) -> None:
        self.emu = emu
        self.elec = emu.electronics
        self.n_channels = len(self.elec.loads)
        self.storage: Any = emu.storage
        self.cause = cause
        self.boot_at = emu.now

    def ticks_ms(self) -> int:
        return self.emu.now - self.boot_at

    def read_currents_ma(self, out: MutableSequence[int]) -> None:
        now = self.emu.now
        read = self.elec.read_ma
        for ch in range(self.n_channels):
            out[ch] = read(ch, now)

    def read_current_ma(self, ch: int) -> int:
        return self.elec.read_ma(ch, self.emu.now)

    def set_switch(self, ch: int, on: bool) -> None:
        self.elec.set_switch(ch, on, self.emu.now)

    def read_switch(self, ch: int) -> bool:
        return self.elec.switches[ch].closed

    def read_input_mv(self) -> int:
        return self.elec.input_mv

    def wdt_feed(self) -> None:
        self.emu.last_feed = self.emu.now

    def reset_cause(self) -> int:
        return self.cause

    def random_bytes(self, n: int) -> bytes:
        # A hardware RNG, as on the board: boot ids and session nonces differ on every run,
        # also under a fixed --seed (which makes only the electronics reproducible).
        return os.urandom(n)

    def reboot(self) -> None:
        self.emu.reboot_requested = True
