"""Record a ROS 2 robot's topics into a rosbag2 MCAP bag: ``dxboard record SYSTEM_DIR BAG``.

Records the topics the robot's topic observers watch (its ``observers:`` section in
``system.yaml``, which must say ``source: {kind: ros2}``, or ``--middleware ros2`` as for
``dxboard run``: the robot ``make run`` starts), ``/board_stream`` (what a running
``dxboard run``'s hardware observer is fed: the board's readings, events and link) when the
robot has a hardware observer, the ROS 2 graph's node list every discovery period (on
``/dxboard/graph``) when it observes node presence from the graph, plus ``/diagnostics`` (the
drivers' and ``dxboard run``'s own), each message as it came over DDS, into the new rosbag2
directory BAG (MCAP storage; ``ros2 bag play`` and Foxglove read it). Until Ctrl-C (or
SIGTERM), or for ``--duration S`` seconds. The DDS domain is the model's ``domain:`` or
``$ROS_DOMAIN_ID``. With ``--journal FILE`` the observers and the diagnoser run on the messages
as they are recorded and the diagnoses go into the journal, as ``dxboard replay`` would write
them from the bag. The recorder subscribes every observed topic before it prints its
"recording" line, and waits (at most ``--wait S``, default 15) until each of them is matched
with the publishers the ROS 2 graph shows, so a fault that starts after that line is in the bag
from its start; topics nobody publishes yet are named on that line and recorded once they appear.
"""

from __future__ import annotations

import argparse
import os
from pathlib import Path

NAME = "record"
HELP = "record a ROS 2 robot's observed topics into a rosbag2 MCAP bag"


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("system_dir", metavar="SYSTEM_DIR", help="robot directory (system.yaml)")
    parser.add_argument("bag", metavar="BAG", help="the bag to create (a new directory)")
    parser.add_argument("--duration", type=float, metavar="S",
                        help="stop after S seconds (default: at Ctrl-C)")
    parser.add_argument("--journal", metavar="FILE",
                        help="journal the live diagnoses into FILE (SQLite) too")
    parser.add_argument("--wait", type=float, default=15.0, metavar="S",
                        help="at most S seconds to match the observed topics' publishers "
                             "before saying 'recording' (default 15)")
    add_middleware(parser)


def add_middleware(parser: argparse.ArgumentParser) -> None:
    """``--middleware`` as ``dxboard run`` takes it (a bag holds ROS 2 topics: ros2)."""
    parser.add_argument("--middleware", choices=("zenoh", "ros2"),
                        default=os.environ.get("DXBOARD_MIDDLEWARE") or None,
                        help="the robot's middleware, as `dxboard run --middleware` (default: "
                             "$DXBOARD_MIDDLEWARE, else the model's observers: source: kind:); "
                             "bags need ros2")


def run(args: argparse.Namespace) -> int:
    import asyncio

    from host.errors import UserError

    if not args.wait >= 0:
        raise UserError(f"--wait {args.wait} is negative", "give a number of seconds, 0 or more")
    if args.duration is not None and not args.duration > 0:
        raise UserError(f"--duration {args.duration} is not positive",
                        "give a number of seconds above 0, or leave it out")
    return asyncio.run(_main(args, Path(args.system_dir), Path(args.bag)))


RECORD_STOP_S = 60.0  # Ctrl-C to exit: closing a large bag can take a while


async def _main(args: argparse.Namespace, system_dir: Path, bag: Path) -> int:
    import asyncio

    from host.commands.bagrun import load_ros_robot, record
    from host.journal import Journal
    from host.launch.signals import StopSignals

    robot = load_ros_robot(system_dir, args.middleware)
    journal = Journal(args.journal) if args.journal else None
    stop = asyncio.Event()
    loop = asyncio.get_running_loop()
    # never lost to a flood of messages; a second Ctrl-C ends it at once (host.launch.signals)
    signals = StopSignals(loop, stop.set, deadline_s=RECORD_STOP_S).install()
    if args.duration is not None:
        loop.call_later(args.duration, stop.set)
    def ready(missing: list[str]) -> None:
        yet = f" (no publisher yet: {', '.join(missing)})" if missing else ""
        print(f"recording {robot.model.name} into {bag}{yet}", flush=True)

    try:
        stats = await record(robot, bag, journal, stop, ready=ready, wait_s=args.wait)
    finally:
        try:
            if journal is not None:
                await journal.flush()
                journal.close()
        finally:
            signals.done()
            signals.close()
    print(f"wrote {bag}: {stats.messages} messages, {stats.bag_s:.1f} s, "
          f"{stats.diagnoses} diagnosis changes", flush=True)
    return 0
