"""Record a robot's ROS 2 topics into a bag while diagnosing them; diagnose a bag again later.

``record(robot, bag, journal, stop)`` subscribes, through the ROS 2 source (``host.ros``), the
topics the robot's topic observers watch, ``/board_stream`` (what a ``dxboard run``'s hardware
observer is fed: ``host.ros.boardstream``) when the robot has a hardware observer, the ROS 2
graph's node list every discovery period (on ``/dxboard/graph``: ``host.ros.graphlog``) when it
has graph observers, plus ``/diagnostics`` (the drivers' and dxboard's own), each once: every
message is written to the bag (``BagWriter``) and fed to the observers, so what is diagnosed
live is exactly what the bag holds. The observers run on ``ClockedObservers``, driven by the
arrivals alone (``step``): each message waits in a ``Reorder`` until an arrival ``GRACE_S`` past
its time (a board item counts at its stamp, a topic message at its arrival), then is fed, and
the observers' deadlines fire up to ``GRACE_S`` before the latest arrival; a replay does the
very same from the bag's arrival times, so the live and the replayed diagnoses are the same
(with nothing arriving at all, the live observers wait for the next message or the end). With a
journal, the diagnoses (``Diagnosing``) are journaled as the daemon journals them.

``replay(robot, bag, journal)`` runs the same observers and the same diagnosis over a bag on
the bag's clock: from the recording's start, every message at its time (in the same
``Reorder``, driven by the arrival times), every deadline at its time, up to the recording's
end, as fast as the bag can be read (no sleeping); the journal it writes has the bag's
times, so ``dxboard report`` draws the timeline of the recorded failure.
Given the same messages, the deadlines fire at the same times: the replay gives the diagnoses
the recording gave.
"""

from __future__ import annotations

import asyncio
import dataclasses
import logging
import time
from collections.abc import Callable, Iterable
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

from host.daemon.core import RobotFiles
from host.daemon.stream import EventStream
from host.errors import UserError
from host.events import JOURNALED, Note, Stamped
from host.journal import Journal
from host.observers.base import Update
from host.observers.payload import TopicMessage
from host.observers.sources.ros2_graph import GRAPH
from host.observers.sources.ros2_message import RosMessage
from host.ros import boardstream, graphlog
from host.ros.bag import NS, Bag, BagWriter
from host.ros.offline import ClockedObservers, Diagnosing, Reorder, bag_observers

if TYPE_CHECKING:
    from host.observers.sources.ros2 import Ros2Source

log = logging.getLogger(__name__)

GRACE_S = 5.0  # how far the live observers run behind the arrivals (a loaded recorder lags)
DIAGNOSTICS = "/diagnostics"


@dataclass
class RunStats:
    messages: int
    bag_s: float  # the span of bag time covered
    wall_s: float  # the wall time it took
    diagnoses: int  # diagnosis records (changes of the bad sets)


def load_ros_robot(system_dir: Path, middleware: str | None = None) -> RobotFiles:
    """The robot directory, checked: a bag holds ROS 2 topics, so it must observe through
    ROS 2 (``middleware``, as ``dxboard run --middleware`` gives it, else the model's
    ``observers: source: {kind: ros2}``)."""
    from host.daemon.core import load_robot

    if not (system_dir / "system.yaml").is_file():
        raise UserError(f"{system_dir}: no system.yaml here",
                        "give a robot directory, e.g. models/tedusar")
    if middleware not in (None, "ros2", "zenoh"):
        raise UserError(f"DXBOARD_MIDDLEWARE={middleware}: not a middleware",
                        "set it to zenoh or ros2, or unset it")
    if middleware == "zenoh":
        raise UserError("--middleware zenoh: a bag holds ROS 2 topics",
                        "run the robot and record it with --middleware ros2")
    robot = load_robot(system_dir, middleware=middleware)
    if robot.observers.source.kind != "ros2":
        raise UserError(f"{system_dir}/system.yaml: the robot observes through "
                        f"{robot.observers.source.kind}, not ROS 2",
                        "give --middleware ros2 (as to `dxboard run`), or set observers: "
                        "source: {kind: ros2} in its system.yaml")
    return robot


def _journaled(journal: Journal | None) -> Callable[[Stamped], None]:
    def record(s: Stamped) -> None:
        if journal is not None and s.event.kind in JOURNALED:
            journal.record(s.event, wall=s.wall, mono=s.mono)
    return record


async def record(robot: RobotFiles, bag_path: Path, journal: Journal | None,
                 stop: asyncio.Event, clock: Callable[[], float] = time.time,
                 ready: Callable[[list[str]], None] | None = None,
                 wait_s: float = 15.0) -> RunStats:
    """Record until ``stop`` is set; the bag is complete when this returns. ``ready`` is
    called once every topic is subscribed and matched with its publishers (at most
    ``wait_s`` later; with the observed topics nobody publishes yet): from then on nothing
    published is missed (``host.ros.matched``)."""
    from host.ros.matched import wait_matched

    spec = robot.observers.source
    stream = EventStream(clock, clock)
    stream.subscribe(_journaled(journal))
    diagnosing = Diagnosing(robot.theory, stream.emit)
    observers = ClockedObservers(bag_observers(robot.observers.observers), diagnosing.apply)
    writer = BagWriter(bag_path)
    source = recorder_source(spec.domain, spec.types, clock)
    waiting = Reorder(GRACE_S)
    last = [clock()]  # the latest arrival

    def on_message(msg: object) -> None:
        if not isinstance(msg, RosMessage):  # a sample of the graph: in the bag's form
            assert isinstance(msg, TopicMessage) and msg.topic == GRAPH
            msg = graphlog.to_bag(msg)
        msg = dataclasses.replace(msg, time=whole_ns(msg.time))  # as the bag will say it
        writer.write(msg)
        last[0] = max(last[0], msg.time)
        step(observers, waiting, msg)

    start = whole_ns(clock())
    t0 = time.perf_counter()
    stream.emit(Note(f"dxboard record {bag_path}: {robot.model.name}"))
    observers.start(start)
    subs = {t: source.subscribe(GRAPH if t == graphlog.TOPIC else t, on_message)
            for t in sorted({*observers.topics, DIAGNOSTICS})}
    try:
        topics = {t: s for t, s in subs.items() if t != graphlog.TOPIC}
        missing = await wait_matched(source, topics, observers.topics, wait_s, stop)
        if ready is not None:
            ready(missing)
        await stop.wait()
    finally:
        for s in subs.values():
            s.close()
        source.close()
        for msg in waiting.drain():
            observers.feed(msg)
        end = whole_ns(max(observers.now if observers.now is not None else start, last[0]))
        observers.advance(end)
        observers.stop()
        stream.emit(Note("dxboard record stopped"))
        writer.close(start, end)
        diagnosing.close()
    return RunStats(writer.count, end - start, time.perf_counter() - t0,
                    len(diagnosing.records))


def recorder_source(domain: int | None, types: Iterable[tuple[str, str]],
                    clock: Callable[[], float]) -> Ros2Source:
    """The recorder's ROS 2 source. Every board item counts (a trip is a few of them), so it
    keeps as many of ``/board_stream``'s messages while it lags as their publisher does
    (``boardstream.DEPTH``, reliable): a recorder held up on a busy machine loses none."""
    from host.observers.sources.ros2 import Ros2Source

    return Ros2Source(domain, dict(types), clock=clock, name="dxboard_recorder",
                      depths={boardstream.TOPIC: boardstream.DEPTH})


def whole_ns(t: float) -> float:
    """``t`` as a bag holds it (whole nanoseconds), so live and replayed times are equal."""
    return round(t * NS) / NS


def step(observers: ClockedObservers, waiting: Reorder, msg: RosMessage) -> None:
    """One message as it arrived (live, or at its time in the bag): it waits in ``waiting``;
    what is ``GRACE_S`` old at its arrival is fed, and the observers' deadlines up to then
    fire. Arrivals alone drive the observers' clock, live as in a replay, so both do the
    same thing in the same order."""
    if msg.topic in observers.topics:
        waiting.push(msg)
    for due in waiting.due(msg.time):
        observers.feed(due)
    observers.advance(msg.time - GRACE_S)


def replay(robot: RobotFiles, bag: Bag, journal: Journal | None) -> RunStats:
    """Diagnose the bag on its own clock; the journal gets the bag's times."""
    now = [bag.start]
    stream = EventStream(lambda: now[0], lambda: now[0])
    stream.subscribe(_journaled(journal))
    diagnosing = Diagnosing(robot.theory, stream.emit)

    def apply(updates: list[Update], t: float) -> None:
        now[0] = t
        diagnosing.apply(updates, t)

    observers = ClockedObservers(bag_observers(robot.observers.observers), apply)
    t0 = time.perf_counter()
    stream.emit(Note(f"dxboard replay {bag.path}: {robot.model.name}"))
    observers.start(bag.start)
    waiting = Reorder(GRACE_S)
    count = 0
    try:
        for msg in bag.messages():
            step(observers, waiting, msg)
            count += 1
        for due in waiting.drain():
            observers.feed(due)
        observers.advance(bag.end)
        now[0] = bag.end
        observers.stop()
        # the end of the data is no evidence: what expired with it is unknown (the last
        # diagnosis says so), and the replay's last word is that the bag ended
        stream.emit(Note(f"bag ended: {count} messages, {bag.end - bag.start:.1f} s"))
    finally:
        diagnosing.close()
    return RunStats(count, bag.end - bag.start, time.perf_counter() - t0,
                    len(diagnosing.records))
