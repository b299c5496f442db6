"""Run the daemon: watch the board, the processes and the topics; diagnose; repair.

``dxboard run SYSTEM_DIR [--board URL | --emulate [--control H:P]] [--web H:P] [--journal FILE]
[--dry-run]`` loads the robot directory (``system.yaml``: the model, its ``observers:`` and
``processes:``; ``repair.pddl``), connects to the board, and then diagnoses on every change of
what the observers see and repairs what it finds (power-cycles, driver restarts), verifying each
step. ``--emulate`` also starts the robot's emulated board (``dxboard emulate``, with its
virtual devices when the robot has them) and prints its board and fault-injection (control)
URLs. It prints one URL a line (``board:``, ``control:``, ``device:``, ``web:``, ``journal:``),
then the run's id (for ``dxboard report --run``) and one line per change of diagnosis, plan,
step result, quarantine and hold, and the board link going down or up (``-q``: only the URLs),
and runs until Ctrl-C or SIGTERM, which stops everything cleanly (it prints ``stopping``, and
every 5 s of a slow stop what it still waits for; each stage of the stop has a deadline, and
the whole stop ends within 9 s; a second Ctrl-C stops at once, killing the nodes and the
emulator, with exit code 130; docs/stopping.md). The robot directory and the addresses are checked
before anything starts. ``kill -USR1 PID`` prints where every thread is, on stderr, for a
report of a daemon that seems stuck.

The key for switching comes from ``$DXBOARD_KEY`` or ``--key-file``; with ``--emulate`` the
emulated board gets the ``--key-file`` key, or a fresh one. ``--dry-run`` diagnoses and plans
but never acts. The web page (read-only) is on 127.0.0.1:8080 unless ``--web`` says otherwise
(``--web off`` for none); the journal is ``dxboard-journal.sqlite`` unless ``--journal`` says
otherwise.
"""

from __future__ import annotations

import argparse
import asyncio
import faulthandler
import logging
import os
import re
import signal
import sys
from pathlib import Path
from typing import TYPE_CHECKING, Any

from host.errors import UserError

if TYPE_CHECKING:
    from host.launch.signals import StopSignals

NAME = "run"
HELP = "run the daemon: observe, diagnose and repair the robot"

log = logging.getLogger(__name__)

LABEL_VALUE = re.compile(r"[A-Za-z0-9_.-]{1,64}")  # --robot, --site: safe in any query or URL


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("system_dir", metavar="SYSTEM_DIR", help="robot directory (models/NAME)")
    where = parser.add_mutually_exclusive_group(required=True)
    where.add_argument("--board", metavar="URL", help="the board, e.g. tcp://192.168.0.7:7000")
    where.add_argument("--emulate", action="store_true",
                       help="start the robot's emulated board and use it")
    parser.add_argument("--control", metavar="H:P", default="127.0.0.1:0",
                        help="with --emulate: the fault-injection endpoint (default: free port)")
    parser.add_argument("--web", metavar="H:P", default="127.0.0.1:8080",
                        help="the web page's address (default 127.0.0.1:8080; 'off' for none)")
    parser.add_argument("--web-allow-origin", metavar="ORIGIN", action="append", default=[],
                        help="another origin whose pages may read the page's API and "
                             "WebSocket, e.g. http://robot7.local:8080 (repeatable; the "
                             "listen address itself, and localhost for a loopback one, always "
                             "may)")
    parser.add_argument("--journal", metavar="FILE", default="dxboard-journal.sqlite",
                        help="the journal file (default dxboard-journal.sqlite)")
    parser.add_argument("--dry-run", action="store_true", help="diagnose and plan, never act")
    parser.add_argument("--key-file", metavar="FILE", help="the board's key (else $DXBOARD_KEY)")
    parser.add_argument("--rate", type=int, default=100, metavar="HZ",
                        help="board readings per second (1-100, default 100)")
    parser.add_argument("--operator", metavar="PATH", type=Path,
                        help="the operator socket for `dxboard quarantine` and `dxboard hold` "
                             "(default: beside the journal, e.g. dxboard-journal.sock)")
    parser.add_argument("-q", "--quiet", action="store_true",
                        help="print only the URLs, not a line per diagnosis, plan, step result "
                             "and quarantine")
    parser.add_argument("--middleware", choices=("zenoh", "ros2"),
                        default=os.environ.get("DXBOARD_MIDDLEWARE") or None,
                        help="the robot's topics on zenoh or ROS 2, for the daemon and the nodes "
                             "it starts (default: $DXBOARD_MIDDLEWARE, else the model's "
                             "observers: source: kind:)")
    parser.add_argument("--zenoh", metavar="ENDPOINT", action="append",
                        help="zenoh endpoint the daemon listens on for topics "
                             "(default: the model's, tcp/127.0.0.1:7447)")
    parser.add_argument("--robot", metavar="NAME", default="",
                        help="this robot's name in the metrics (label robot) and on the page "
                             "(default: the model's name); unique in a fleet")
    parser.add_argument("--site", metavar="NAME", default="default",
                        help="where the robot works, the label site of every metric "
                             "(default 'default'); see docs/fleet.md")


def run(args: argparse.Namespace) -> int:
    from host.launch.signals import StopSignals
    from host.web.guard import parse_origin
    from host.web.server import parse_listen

    system_dir = Path(args.system_dir)
    if not (system_dir / "system.yaml").is_file():
        raise UserError(f"{system_dir}: no system.yaml here",
                        "give a robot directory, e.g. models/tedusar")
    web = None if args.web == "off" else parse_listen(args.web)
    for flag, value in (("--robot", args.robot), ("--site", args.site)):
        if value and not LABEL_VALUE.fullmatch(value):
            raise UserError(f"{flag} {value!r}: not a name",
                            f"give {flag} letters, digits, '_', '-' or '.' (e.g. rover-7)")
    for origin in args.web_allow_origin:
        try:
            parse_origin(origin)
        except ValueError as exc:
            raise UserError(f"--web-allow-origin {exc}", "give scheme://host[:port]") from None
    if not 1 <= args.rate <= 100:
        raise UserError(f"--rate {args.rate} is out of range", "give 1..100")
    state = _State()
    # the runner's teardown (cancelling what is left, joining its executor) stays under the
    # signals' watchdog: a stop ends within its deadline even if that hangs
    with asyncio.Runner() as runner:
        signals = StopSignals(runner.get_loop(), state.request_stop).install()
        try:
            return runner.run(_main(args, system_dir, web, state, signals))
        except asyncio.CancelledError:  # stopped while starting up
            print("stopped before the robot was up", file=sys.stderr)
            return 0
        finally:
            runner.close()
            signals.done()
            signals.close()


class _State:
    """What a stop request has to reach: the stop event once running, the starting task."""

    def __init__(self) -> None:
        self.stop = asyncio.Event()
        self.running = False
        self.main: asyncio.Task[Any] | None = None

    def request_stop(self) -> None:  # on the loop, at the first SIGINT/SIGTERM
        self.stop.set()
        if not self.running and self.main is not None:
            self.main.cancel()  # still starting: unwind the start (bounded like a stop)


async def _main(args: argparse.Namespace, system_dir: Path, web: tuple[str, int] | None,
                state: _State, signals: StopSignals) -> int:
    from host.board.keys import load_key
    from host.commands.terminal import TerminalLines
    from host.daemon import memprobe
    from host.daemon.core import DaemonOptions
    from host.launch.robot import Launch, LaunchedRobot
    from host.launch.stopping import Stopping
    from host.operator.client import default_socket

    state.main = asyncio.current_task()
    stop = state.stop
    terminal: TerminalLines | None = None
    stopping: Stopping | None = None
    faulthandler.register(signal.SIGUSR1, all_threads=True)  # where it is, for a bug report
    memprobe.install(signals.on)  # off unless $DXBOARD_MEMPROBE is set
    try:
        key = load_key(args.key_file) if (args.key_file or not args.emulate) else None
        journal = Path(args.journal)
        opts = DaemonOptions(system_dir=system_dir, board_url=args.board or "", web=web,
                             web_allow_origins=tuple(args.web_allow_origin),
                             journal=journal, dry_run=args.dry_run,
                             rate_hz=args.rate, zenoh_listen=args.zenoh,
                             middleware=args.middleware, robot=args.robot, site=args.site,
                             operator=args.operator or default_socket(journal))
        launch = Launch(system_dir, None if args.emulate else args.board, key,
                        control=args.control, daemon=opts)
        terminal = None if args.quiet else TerminalLines(paused=True)
        if terminal is not None:
            launch.readers = (terminal,)
        robot = LaunchedRobot(launch)
        stopping = Stopping(lambda: robot.closing)  # says what a slow stop waits for
        await robot.__aenter__()  # a stop request meanwhile cancels it: it unwinds, bounded
        state.running = True
        try:
            for line in robot.lines():
                print(line)
            sys.stdout.flush()
            if terminal is not None:
                terminal.resume()
            waiter = asyncio.ensure_future(robot.daemon.wait())
            stopper = asyncio.ensure_future(stop.wait())
            done, _ = await asyncio.wait([waiter, stopper], return_when=asyncio.FIRST_COMPLETED)
            for task in (waiter, stopper):
                if task not in done:
                    task.cancel()
            if waiter in done:
                waiter.result()  # a failed task: raise it
            if terminal is not None:
                terminal.say("stopping")
        finally:
            signals.begin()  # whatever ended the run, its stop is bounded
            stopping.start()
            await robot.close()
        return 0
    finally:
        if stopping is not None:
            stopping.done()
        if terminal is not None:
            terminal.close()
