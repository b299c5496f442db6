"""The emulated board: the firmware (``firmware.app.App``) on ``SimHal`` and ``Electronics``.

Time is ``self.now`` in ms on a simulated clock. ``advance(ms)`` runs every firmware step due in
that span, tick by tick, as fast as the host computer allows (ten simulated minutes take
seconds); ``control.run_wallclock`` calls ``advance`` to keep up with the wall clock instead.
Both run the same steps in the same order, so a scenario behaves the same on either clock.

Resets are the emulator's job, as they are the hardware's: ``reboot`` from the firmware gives a
soft reset; ``wdt_reset`` hangs the firmware's main loop (its steps stop) so that the watchdog,
no longer fed by the supervisor, resets the board after ``wdt_timeout_ms``; a ``brownout``
below ``reset_mv`` holds the microcontroller in reset (every switch opens, every connection
drops: ``reset_listeners``; nothing runs and nothing is served) until the voltage returns,
then boots with ``RESET_BROWNOUT``; a shallower one only lowers the input the firmware
measures. Each boot builds a new ``App`` on a new ``SimHal``; storage and electronics persist.

Runtime seam: everything the firmware sees passes through ``SimHal``'s methods, and the
emulator only calls ``firmware.start()``, ``firmware.step()`` and reads ``firmware.board``. A
``--runtime micropython`` firmware is therefore an object with those three members whose HAL
calls cross a pipe to a ``micropython`` subprocess running ``firmware.app.App`` on a proxy HAL
(lock-step: the emulator sends each step's clock, currents, switch read-backs and input voltage;
the subprocess answers with its switch commands, feeds and status), with the electronics and the
clock staying here.

Link faults (``link_*``) do nothing here: they are recorded in ``link_faults`` and announced to
``link_listeners`` for the front ends, which will apply them to their byte streams.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

from emulator import faults as F
from emulator.electronics import Electronics
from emulator.hal import SimHal
from emulator.model import EmulatorModel, EmulatorModelError
from firmware import config
from firmware.app import App
from firmware.hal.storage import MemStorage
from protocol import settings
from protocol.constants import (
    FAULT_NAMES,
    RESET_BROWNOUT,
    RESET_NAMES,
    RESET_POWER_ON,
    RESET_SOFT,
    RESET_WATCHDOG,
    STATE_NAMES,
)
from protocol.events import flag_names

BOARD = "board"


class Emulator:
    def __init__(self, model: EmulatorModel, storage: Any = None,
                 board_config: dict[str, Any] | None = None,
                 firmware_factory: Callable[[SimHal], Any] | None = None) -> None:
        """``firmware_factory(hal)`` builds the firmware of each boot (default ``App``: the
        firmware in this interpreter; ``emulator.mpy.MicroFirmware`` runs it in MicroPython).
        ``board_config`` (channels/board fields, as in ``models/<robot>/board.json``) is what
        flashing a board does with it: built into the firmware as its factory configuration
        (``factory``, booted when no stored copy is good) and written to storage as the
        persisted configuration if storage holds none yet."""
        self.model = model
        self.now = 0
        self.storage: Any = storage if storage is not None else MemStorage()
        self.electronics = Electronics(list(model.channels), model.board.input_mv,
                                       model.board.seed)
        # what flashing the board built into its firmware: its factory configuration
        self.factory = make_config(board_config, len(model.channels)) \
            if board_config is not None else None
        if self.factory is not None and not config.exists(self.storage):
            config.save(self.storage, self.factory)
        self.active: dict[tuple[str, str], dict[str, Any]] = {}
        self.link_faults: dict[str, dict[str, Any]] = {}
        self.link_listeners: list[Callable[[dict[str, dict[str, Any]]], None]] = []
        # called after every firmware step (front ends push what the step produced)
        self.step_listeners: list[Callable[[], None]] = []
        # called when the microcontroller goes into reset (a deep brown-out): the front ends
        # drop every connection and serve nothing until the next boot
        self.reset_listeners: list[Callable[[], None]] = []
        self.firmware_factory: Callable[[SimHal], Any] = firmware_factory or self._app
        self.timers: list[tuple[int, Callable[[], None]]] = []
        self.last_feed = 0
        self.reboot_requested = False
        self.hung = False
        self.down_until = -1
        self.boots: list[tuple[int, int]] = []  # (time, reset cause) of every boot
        self.next_due = 0
        # the part models of a ``--board-rev`` board (``emulator.board_rt.BoardRuntime``):
        # ``inject_part(ch, fault, params)``, ``reinject_part`` (after a clear) and
        # ``clear_parts(ch)``; None: the faults of scope "part" are refused
        self.parts: Any = None
        self.firmware: Any
        self._boot(RESET_POWER_ON)

    # --- clock and resets ---------------------------------------------------------------

    def _app(self, hal: SimHal) -> App:
        return App(hal, self.factory)

    def _boot(self, cause: int) -> None:
        self.electronics.release_all(self.now)
        self.hung = False
        self.reboot_requested = False
        self.active.pop((BOARD, "wdt_reset"), None)
        hal = SimHal(self, cause)
        self.hal = hal
        self.firmware = self.firmware_factory(hal)
        self.firmware.start()
        self.last_feed = self.now
        self.boots.append((self.now, cause))
        self.next_due = self.now

    @property
    def board(self) -> Any:
        return self.firmware.board

    @property
    def in_reset(self) -> bool:
        """Held in reset by a deep brown-out: the microcontroller runs nothing at all."""
        return self.down_until >= 0

    def at(self, when_ms: int, action: Callable[[], None]) -> None:
        """Run ``action`` when the clock reaches ``when_ms`` (scenario events, fault ends)."""
        self.timers.append((when_ms, action))
        self.timers.sort(key=lambda t: t[0])

    def advance(self, ms: int) -> None:
        self.advance_to(self.now + ms)

    def advance_to(self, end: int) -> None:
        while True:
            due = self.next_due
            if self.timers and self.timers[0][0] < due:
                due = self.timers[0][0]
            if due > end:
                break
            self.now = max(self.now, due)
            while self.timers and self.timers[0][0] <= self.now:
                self.timers.pop(0)[1]()
            if self.now >= self.next_due:
                self._step()
        self.now = max(self.now, end)

    def _step(self) -> None:
        tick = 10
        if self.down_until >= 0:  # held in reset by a brown-out
            self.next_due = self.now + tick
            return
        if self.hung:
            if self.now - self.last_feed > self.model.board.wdt_timeout_ms:
                self._boot(RESET_WATCHDOG)
            else:
                self.next_due = self.now + tick
            return
        due = self.firmware.step()
        for listener in self.step_listeners:
            listener()
        if self.reboot_requested:
            self._boot(RESET_SOFT)
            return
        self.next_due = self.hal.boot_at + due

    # --- faults -------------------------------------------------------------------------

    def channel_index(self, channel: str | int) -> int:
        try:
            return self.model.index(channel)
        except EmulatorModelError:
            pass
        if isinstance(channel, str):
            for i in range(len(self.model.channels)):
                if self.board.get_channel_config(i)[1]["name"] == channel:
                    return i
        raise F.FaultError(
            f"no channel {channel!r}: use {BOARD!r}, 0..{len(self.model.channels) - 1} or "
            + ", ".join(c.name for c in self.model.channels))

    def inject(self, channel: str | int, fault: str, raw: dict[str, Any]) -> dict[str, Any]:
        """Inject ``fault`` with raw (string or typed) parameters; returns what was applied."""
        params = F.parse_params(fault, raw)
        if F.scope(fault) == BOARD:
            if str(channel) != BOARD:
                raise F.FaultError(f"{fault} is a board fault: use channel {BOARD!r}")
            self._inject_board(fault, params)
            return {"channel": BOARD, "fault": fault, "params": params}
        if str(channel) == BOARD:
            raise F.FaultError(f"{fault} is a channel fault: name a channel, not {BOARD!r}")
        ch = self.channel_index(channel)
        if F.scope(fault) == "part":
            if self.parts is None:
                raise F.FaultError(f"{fault} is a fault of a part model: only a board "
                                   "emulated with --board-rev has them")
            self.parts.inject_part(ch, fault, params)
        else:
            self.electronics.inject(ch, fault, params, self.now)
        self.active[(str(ch), fault)] = params
        return {"channel": ch, "fault": fault, "params": params}

    def _inject_board(self, fault: str, params: dict[str, Any]) -> None:
        self.active[(BOARD, fault)] = params
        if fault == "wdt_reset":
            self.hung = True
        elif fault == "brownout":
            self.electronics.input_mv = int(params["volts"] * 1000)
            end = self.now + int(params["seconds"] * 1000)
            if self.electronics.input_mv < self.model.board.reset_mv:
                self.down_until = end
                self.electronics.release_all(self.now)
                for listener in self.reset_listeners:
                    listener()
            self.at(end, self._brownout_over)
        else:
            self.link_faults[fault] = params
            self._announce_link()

    def _brownout_over(self) -> None:
        if (BOARD, "brownout") not in self.active:
            return
        self.active.pop((BOARD, "brownout"), None)
        self.electronics.input_mv = self.electronics.nominal_mv
        if self.down_until >= 0:
            self.down_until = -1
            self._boot(RESET_BROWNOUT)

    def _announce_link(self) -> None:
        for listener in self.link_listeners:
            listener(dict(self.link_faults))

    def clear(self, channel: str | int | None = None, fault: str | None = None) -> None:
        """Clear every fault, one channel's (or the board's), or one fault of it."""
        if channel is None:
            keys = list(self.active)
        else:
            where = BOARD if str(channel) == BOARD else str(self.channel_index(channel))
            keys = [k for k in self.active if k[0] == where and fault in (None, k[1])]
        for where, name in keys:
            self.active.pop((where, name), None)
            if where == BOARD:
                self._clear_board(name)
        for ch in {int(w) for w, _ in keys if w != BOARD}:
            self.electronics.clear(ch, self.now)
            if self.parts is not None:
                self.parts.clear_parts(ch)
            for (w, name), params in list(self.active.items()):
                if w != str(ch):
                    continue
                if F.scope(name) == "part":
                    self.parts.reinject_part(ch, name, params)
                else:
                    self.electronics.inject(ch, name, params, self.now)

    def _clear_board(self, fault: str) -> None:
        if fault == "wdt_reset":
            self.hung = False
        elif fault == "brownout":
            self.electronics.input_mv = self.electronics.nominal_mv
            if self.down_until >= 0:
                self.down_until = -1
                self._boot(RESET_BROWNOUT)
        elif self.link_faults.pop(fault, None) is not None:
            self._announce_link()

    def faults(self) -> list[dict[str, Any]]:
        return [{"channel": w if w == BOARD else int(w), "fault": f, "params": p}
                for (w, f), p in sorted(self.active.items())]

    # --- status -------------------------------------------------------------------------

    def status(self) -> dict[str, Any]:
        """The firmware's status, with names, plus what only the emulator knows (truth)."""
        from protocol.constants import BOARD_FLAG_NAMES, CONFIG_STATUS_NAMES

        b, chans = self.board.status()
        out: dict[str, Any] = {
            "now_ms": self.now, "input_mv": b[0], "total_ma": b[1], "uptime_ms": b[2],
            "reset_cause": RESET_NAMES[b[3]], "config_status": CONFIG_STATUS_NAMES[b[4]],
            "flags": flag_names(b[5], BOARD_FLAG_NAMES), "boots": len(self.boots),
            "channels": [],
        }
        for i, c in enumerate(chans):
            load = self.electronics.loads[i]
            out["channels"].append({
                "channel": i, "name": self.board.get_channel_config(i)[1]["name"],
                "commanded": c[0], "physical": c[1], "state": STATE_NAMES[c[2]],
                "current_ma": c[3], "live": flag_names(c[4], FAULT_NAMES),
                "sticky": flag_names(c[5], FAULT_NAMES), "trips": c[6], "retries": c[7],
                "true_ma": round(load.current_ma(self.now)), "ready": load.ready(self.now),
            })
        return out


def make_config(board_config: dict[str, Any], n: int) -> dict[str, Any]:
    """A full firmware configuration from a model's partial one; ``EmulatorModelError`` if
    invalid."""
    cfg, bad = settings.merge(board_config, n, config.VERSION)
    if cfg is None:
        raise EmulatorModelError(f"board config: bad field {bad}")
    result: dict[str, Any] = cfg
    return result
