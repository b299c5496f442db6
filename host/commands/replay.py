"""Diagnose a recorded bag again: ``dxboard replay BAG SYSTEM_DIR --journal FILE``.

Runs the topic observers and the hardware observer of the robot's ``observers:`` section
(``source: {kind: ros2}``, or ``--middleware ros2`` as for ``dxboard run``; the hardware
observer is fed the board's items from the bag's ``/board_stream``, which a ``dxboard run`` on
ROS 2 publishes, each at its stamp) and the diagnoser over the rosbag2 bag BAG (MCAP or SQLite;
``dxboard record`` or ``ros2 bag record`` wrote it) on the bag's clock: every message at its
recorded time, every observer deadline at its time, as fast as the bag can be read. The journal
FILE gets the observations and the diagnoses with the bag's times, so ``dxboard report FILE -o
timeline.png`` draws the timeline of the recorded failure. Node presence from the ROS 2 graph is
replayed from the graph samples ``dxboard record`` wrote (``/dxboard/graph``); process observers
are not (not yet: a bag holds no supervisor).
"""

from __future__ import annotations

import argparse

from host.commands.record import add_middleware

NAME = "replay"
HELP = "diagnose a recorded rosbag2 bag on its own clock into a journal"


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("bag", metavar="BAG", help="rosbag2 bag (directory or .mcap file)")
    parser.add_argument("system_dir", metavar="SYSTEM_DIR", help="robot directory (system.yaml)")
    parser.add_argument("--journal", required=True, metavar="FILE",
                        help="the journal to write (SQLite)")
    add_middleware(parser)


def run(args: argparse.Namespace) -> int:
    from pathlib import Path

    from host.commands.bagrun import load_ros_robot, replay
    from host.journal import Journal
    from host.ros.bag import Bag

    robot = load_ros_robot(Path(args.system_dir), args.middleware)
    bag = Bag(Path(args.bag))
    try:
        journal = Journal(args.journal)
        try:
            stats = replay(robot, bag, journal)
        finally:
            journal.flush_blocking()
            journal.close()
    finally:
        bag.close()
    speed = stats.bag_s / stats.wall_s if stats.wall_s > 0 else float("inf")
    print(f"replayed {bag.path}: {stats.messages} messages, {stats.bag_s:.1f} s of bag in "
          f"{stats.wall_s:.2f} s ({speed:.0f}x), {stats.diagnoses} diagnosis changes "
          f"into {args.journal}")
    return 0
