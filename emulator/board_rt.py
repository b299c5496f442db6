"""``--board-rev REV``: the shipped ``boot.py`` and ``main.py`` on part models, in lock-step.

``BoardRuntime`` starts ``micropython -m emulator.parts.bench`` (protocol there) in the board's
flash directory (the files ``dxboard flash`` writes: ``board_rev``, the stored configuration),
with ``emulator/parts/clock`` and ``emulator/parts`` first on ``MICROPYPATH``, so that the
unmodified firmware's ``import machine``, ``import network`` and ``import time`` get the part
models and the simulated clock. Where ``MicroRuntime`` (``emulator/mpy.py``, whose links this
extends) runs ``App`` on a remote HAL that is handed currents, this runs the board's own HAL
(``firmware/hal/target.py``) against register-level chips: the ``World`` lives in the
micropython process, and each emulator step sends the electrical inputs the simulated
electronics (``emulator/electronics.py``) give at that instant, per channel the current through
the shunt (the sensor faults of the electronics included) and the switch's output, plus the
input voltage; the clock moves to the step's time there, everything the firmware has due by
then runs, and the answer says when its next timer is due. The enable pins come back on link B
the moment the firmware drives them (``set_switch`` on the electronics); the UART's wires are
link U, relayed to the pty of ``--serial``.

The Modbus server of ``main.py`` (its port 502) listens directly on the ``--modbus`` address,
so it sees each client's own address as on a network; the native protocol (its port 7000)
sits behind the link-fault proxies of ``FrontEnds``. Resets stay the emulator's (``sim.py``):
a reset the firmware makes itself comes back as ``reboot`` in a step's answer. Part faults
(``emulator/faults.py``) go to the part that senses the channel, as ``emulator.parts.wiring``
wired it: ``chip_*`` to a shunt monitor (rev A, rev B), ``switch_*`` to that channel of a
smart switch (rev C); a revision whose part has no such fault refuses it in one line.
"""

from __future__ import annotations

import asyncio
import os
from collections.abc import Callable
from pathlib import Path
from typing import Any

from emulator.faults import FaultError
from emulator.frontends import FrontEnds
from emulator.hal import SimHal
from emulator.mpy import ROOT, MicroFirmware, MicroRuntime, find_micropython, free_port
from firmware import boards

BOOT_TIMEOUT_S = 60.0  # the first boot compiles every firmware module (slow on a loaded host)
# part fault of the emulator (``emulator/faults.py``) -> the chip model's fault and its value
PART_FAULTS: dict[str, tuple[str, Callable[[dict[str, Any]], Any]]] = {
    "chip_nack": ("nack", lambda p: True),
    "chip_stuck_low": ("stuck_low", lambda p: True),
    "chip_reset": ("reset", lambda p: True),
    "chip_stuck": ("stuck", lambda p: True),
    "chip_open_shunt": ("open_shunt", lambda p: True),
    "chip_gain": ("gain", lambda p: p["factor"]),
    "chip_noise": ("noise", lambda p: p["volts"]),
    "chip_die_id": ("die_id", lambda p: int(p["id"])),
    "switch_short": ("short", lambda p: p["amps"]),
    "switch_overtemp": ("overtemp", lambda p: True),
    "switch_open_load": ("open_load", lambda p: True),
}
# a revision's sense part (``sense["chip"]`` of ``firmware/boards``) -> the part faults it has
CHIP_FAULTS = tuple(f for f in PART_FAULTS if f.startswith("chip_"))
SWITCH_FAULTS = tuple(f for f in PART_FAULTS if f.startswith("switch_"))
PART_OF: dict[str, tuple[str, ...]] = {"ina226": CHIP_FAULTS, "ina3221": CHIP_FAULTS,
                                       "profet": SWITCH_FAULTS}
FLASHED_TUG_PORT = 5000  # ``tug_port`` flashed for ``--tug`` (the original board's port)
ONE_SHOT = ("chip_reset",)  # happens once: not applied again when other faults are cleared


class BoardRuntime(MicroRuntime):
    def __init__(self, rev: str, flash: Path, modbus: tuple[str, int] | None = None,
                 micropython: str | None = None, tug: bool = False) -> None:
        self.rev = rev
        self.chip = boards.load(rev)["sense"]["chip"]
        self.flash = flash
        self.tcp_port = free_port()
        self.modbus_at = modbus
        self.modbus_port = (modbus[1] or free_port()) if modbus is not None else free_port()
        self.serial_port = None
        self.tug_port = free_port() if tug else None  # where main.py's tug_port listens
        self.tug_switch = False  # the flashed configuration's tug_switch decides on the board
        self.can = False
        self.can_out = []
        self.caps = 0
        self.hal: SimHal | None = None
        (flash / "board_rev").write_text(rev + "\n")  # as `dxboard flash --board-rev` does
        paths = [ROOT / "emulator" / "parts" / "clock", ROOT / "emulator" / "parts"]
        env = dict(os.environ, MICROPYPATH=":".join([*map(str, paths), ".frozen", str(ROOT)]))
        links = self._spawn(lambda port: [
            micropython or find_micropython(), "-m", "emulator.parts.bench", "127.0.0.1",
            str(port), rev, str(self.tcp_port), str(self.modbus_port), str(self.tug_port or 0)],
            env, flash, (b"A", b"B", b"U"))
        self.a = links[b"A"]
        self.b = links[b"B"]
        self.u = links[b"U"]

    def factory(self, hal: SimHal) -> BoardFirmware:
        return BoardFirmware(self, hal)

    async def start_frontends(self, fronts: FrontEnds, listen: tuple[str, int],
                              modbus_at: tuple[str, int] | None, serial: bool,
                              can: str | None,
                              tug_at: tuple[str, int] | None = None) -> dict[str, str]:
        """The native protocol behind the proxies, Modbus direct, the pty relayed to link U,
        and the original TEDUSAR format (``tug_port`` flashed) behind a proxy too."""
        asyncio.get_running_loop().add_reader(self.b.sock.fileno(), self._serve_b)
        fronts.emu.reset_listeners.append(self.halt)
        host, port = await fronts.proxy_to(("127.0.0.1", self.tcp_port), listen)
        fronts.urls["board"] = f"tcp://{host}:{port}"
        if modbus_at is not None:
            fronts.urls["modbus"] = f"modbus+tcp://127.0.0.1:{self.modbus_port}"
        if serial:
            await fronts.start_serial(relay_to=self.u.sock)
        if tug_at is not None and self.tug_port is not None:
            host, port = await fronts.proxy_to(("127.0.0.1", self.tug_port), tug_at)
            fronts.urls["tug"] = f"tug://{host}:{port}"
        return fronts.urls

    # --- part faults (``Emulator.parts``) ---------------------------------------------------

    def inject_part(self, ch: int, fault: str, params: dict[str, Any]) -> None:
        has = PART_OF.get(self.chip, ())
        if fault not in has:
            raise FaultError(f"{fault}: the {self.rev} board senses with {self.chip}, which has "
                             f"no such fault (its part faults: {', '.join(has) or 'none'})")
        name, value = PART_FAULTS[fault]
        self.request({"op": "part", "ch": ch, "fault": name, "value": value(params)})

    def reinject_part(self, ch: int, fault: str, params: dict[str, Any]) -> None:
        if fault not in ONE_SHOT:
            self.inject_part(ch, fault, params)

    def clear_parts(self, ch: int) -> None:
        self.request({"op": "part_clear", "ch": ch})

    def registers(self, ch: int) -> list[int]:
        """The registers of the chip that senses channel ``ch``, as it holds them now."""
        regs: list[int] = self.request({"op": "regs", "ch": ch})["regs"]
        return regs


class BoardFirmware(MicroFirmware):
    """One boot of the shipped firmware on the bench, as the emulator sees it."""

    rt: BoardRuntime

    def start(self) -> None:
        self.rt.hal = self.hal
        self.rt.request({"op": "boot", "cause": self.hal.cause, "t": self.hal.emu.now,
                         "mv": self.hal.read_input_mv()}, BOOT_TIMEOUT_S)

    def step(self) -> int:
        hal = self.hal
        n = hal.n_channels
        now = hal.emu.now
        ma = [0] * n
        hal.read_currents_ma(ma)
        rep = self.rt.request({"op": "step", "t": now, "ma": ma, "mv": hal.read_input_mv(),
                               "sw": [hal.read_switch(i) for i in range(n)]})
        if rep["feeds"]:
            hal.wdt_feed()
        if rep["reboot"]:
            hal.reboot()
        at: int = rep["at"]
        return at - hal.boot_at
