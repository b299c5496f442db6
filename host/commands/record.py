"""Record a ROS 2 robot's topics into a rosbag2 MCAP bag: ``dxboard record SYSTEM_DIR BAG``.

Records the topics the robot's topic observers watch (its ``observers:`` section in
``system.yaml``, which must say ``source: {kind: ros2}``), ``/board_stream`` (what a running
``dxboard run``'s hardware observer is fed: the board's readings, events and link) when the
robot has a hardware observer, the ROS 2 graph's node list every discovery period (on
``/dxboard/graph``) when it observes node presence from the graph, plus ``/diagnostics`` (the
drivers' and ``dxboard run``'s own), each message as it came over DDS, into the new rosbag2
directory BAG (MCAP storage; ``ros2 bag play`` and Foxglove read it). Until Ctrl-C (or
SIGTERM), or for ``--duration S`` seconds. The DDS domain is the model's ``domain:`` or
``$ROS_DOMAIN_ID``. With ``--journal FILE`` the observers and the diagnoser run on the messages
as they are recorded and the diagnoses go into the journal, as ``dxboard replay`` would write
them from the bag.
"""

from __future__ import annotations

import argparse
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


def run(args: argparse.Namespace) -> int:
    import asyncio

    from host.errors import UserError

    if args.duration is not None and not args.duration > 0:
        raise UserError(f"--duration {args.duration} is not positive",
                        "give a number of seconds above 0, or leave it out")
    return asyncio.run(_main(args, Path(args.system_dir), Path(args.bag)))


async def _main(args: argparse.Namespace, system_dir: Path, bag: Path) -> int:
    import asyncio
    import signal

    from host.commands.bagrun import load_ros_robot, record
    from host.journal import Journal

    robot = load_ros_robot(system_dir)
    journal = Journal(args.journal) if args.journal else None
    stop = asyncio.Event()
    loop = asyncio.get_running_loop()
    for sig in (signal.SIGINT, signal.SIGTERM):
        loop.add_signal_handler(sig, stop.set)
    if args.duration is not None:
        loop.call_later(args.duration, stop.set)
    print(f"recording {robot.model.name} into {bag}", flush=True)
    try:
        stats = await record(robot, bag, journal, stop)
    finally:
        if journal is not None:
            await journal.flush()
            journal.close()
    print(f"wrote {bag}: {stats.messages} messages, {stats.bag_s:.1f} s, "
          f"{stats.diagnoses} diagnosis changes", flush=True)
    return 0
