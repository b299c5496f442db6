"""Start an emulated board: the real firmware on simulated electronics, reachable like a board.

``dxboard emulate SYSTEM_DIR [--listen H:P] [--control H:P] [--modbus H:P] [--serial]
[--can INTERFACE:CHANNEL] [--tug H:P [--tug-switch]] [--runtime cpython|micropython]
[--scenario FILE] [--seed N] [--key-file FILE] [--robot [--world]] [--flash DIR]
[--board-rev REV]`` loads
``SYSTEM_DIR/emulator.yaml`` (the loads) and ``board.json`` (the board configuration, written
to the emulated flash on first boot; ``--flash DIR`` keeps that flash in a directory, so that
``config save`` survives a restart), boots the firmware, starts its front ends and prints one
URL a line, then runs on the wall clock until SIGINT/SIGTERM::

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
inside the ``micropython`` interpreter: its own TCP, Modbus and tug servers (behind the same
link-fault proxies), its serial front end (the pty's bytes relayed to it) and its CAN node
(frames carried between the bus and it), so every front end runs there too.
``--board-rev REV`` (with ``--runtime micropython``) boots instead the shipped
``firmware/boot.py`` and ``firmware/main.py``, unmodified, on register-level models of that
revision's parts (``emulator.board_rt``): its own HAL reads the chips over the model of
``machine.I2C`` (rev A, rev B) or the smart switches over ``machine.ADC`` (rev C), fed by the
same simulated electronics in lock-step; the part faults (``dxboard inject ... chip_nack`` and
the other ``chip_*``; ``switch_*`` on rev C) reach those parts. ``main.py``
serves no CAN, and the original TEDUSAR format only as flashed: ``--tug`` flashes its
configuration with ``tug_port`` 5000 (and ``tug_switch`` as ``--tug-switch`` says; a ``--flash``
directory that already holds a stored configuration keeps its own); its Modbus server listens
on ``--modbus`` directly. An unknown revision is refused with the known ones.
``--tug`` serves the original TEDUSAR board's format (``firmware/tug.py``), which has no
authentication: read-only unless ``--tug-switch`` is given, and even then it never switches a
protected channel off.
``--robot`` also serves the virtual robot's devices of ``SYSTEM_DIR/robot.yaml`` (each on a
free TCP port, powered by its channel: ``emulator.robot``) for the nodes of
``python -m emulator.robot.node NAME SYSTEM_DIR`` to read. ``--world`` also serves the world the
robot acts in (``SYSTEM_DIR/arena/world.yaml``, a pyrobosim arena: ``emulator.robot.world``):
its skill servers (navigate, detect, mark, open, level) move and sense only as the board, the
devices and their drivers allow.

This module only reads the command line and the key; the emulator itself is
``emulator.main.run``, which installs its SIGTERM/SIGINT handlers before it prints anything.
"""

from __future__ import annotations

import argparse
import sys

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
    parser.add_argument("--flash", metavar="DIR",
                        help="keep the board's flash (saved configuration, boot record) in "
                             "this directory, so that it survives a restart; default: memory")
    parser.add_argument("--board-rev", metavar="REV",
                        help="with --runtime micropython: boot the shipped boot.py and main.py "
                             "of this board revision (firmware/boards, e.g. rev-a) on "
                             "register-level models of its parts")
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
    from pathlib import Path

    from emulator.main import Options, StartError
    from emulator.main import run as run_emulator
    from host.board.keys import load_key

    if args.tug_switch and not args.tug:
        raise UserError("--tug-switch needs --tug H:P", "add --tug 127.0.0.1:5000, say")
    if args.board_rev is not None:
        from host.commands.flash import check_revision

        check_revision(args.board_rev)
        if args.runtime != "micropython":
            raise UserError("--board-rev needs --runtime micropython",
                            "add --runtime micropython: the shipped main.py runs there")
        if args.can:
            raise UserError("--can with --board-rev: the shipped main.py serves no CAN",
                            "drop --can, or use --runtime micropython without --board-rev")
    if args.world and not args.robot:
        raise UserError("--world needs --robot", "add --robot: the world moves the robot's devices")
    opts = Options(
        system_dir=Path(args.system_dir),
        listen=parse_address(args.listen, "--listen"),
        control=parse_address(args.control, "--control"),
        modbus=parse_address(args.modbus, "--modbus") if args.modbus else None,
        serial=args.serial,
        can=parse_can(args.can) if args.can else None,
        tug=parse_address(args.tug, "--tug") if args.tug else None,
        tug_switch=args.tug_switch,
        runtime=args.runtime,
        scenario=Path(args.scenario) if args.scenario else None,
        seed=args.seed,
        key=load_key(args.key_file),
        robot=args.robot,
        world=args.world,
        flash=Path(args.flash) if args.flash else None,
        board_rev=args.board_rev,
    )
    try:
        return run_emulator(opts, sys.stdout)
    except StartError as exc:
        raise UserError(exc.message, exc.hint) from None
