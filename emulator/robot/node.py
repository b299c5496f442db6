"""A node of the virtual robot as an OS process: ``python -m emulator.robot.node NAME [DIR]``.

``NAME`` is a node component (N, HN or SN) of ``DIR/system.yaml``; what it does is in
``emulator.robot.behaviours``. The environment gives the rest:

    DXBOARD_ROBOT    the robot directory when DIR is not given (the daemon sets it for every
                     process it starts)
    DXBOARD_ZENOH    the zenoh endpoint to connect to (default tcp/127.0.0.1:7447: the daemon)
    DXBOARD_ZENOH_AUTH  the daemon's zenoh credentials file (user:password), when its endpoint
                     requires authentication (``dxboard run`` sets it for the nodes it starts)
    DXBOARD_MIDDLEWARE  zenoh or ros2: overrides the robot's setting (``observers: source:
                     kind:`` of system.yaml; ros2 there makes the nodes ROS 2 nodes)
    ROS_DOMAIN_ID    ROS 2 mode: the DDS domain (rclpy reads it)
    DXBOARD_DEVICES  drivers only: a JSON object device name -> tcp://HOST:PORT, as
                     ``dxboard emulate SYSTEM_DIR --robot`` prints them

In ROS 2 mode (``emulator.robot.ros_bus``) the node is an rclpy node named ``NAME`` publishing
standard messages (``emulator.robot.ros_msgs``), and a driver also publishes its health on
``/diagnostics`` once a second (``emulator.robot.driver_status``). ``--managed`` makes a driver
a ROS 2 managed (lifecycle) node in ROS 2 mode (``emulator.robot.managed``); in Zenoh mode,
which has no lifecycle, it is ignored.

``--exit-without-device[=SECONDS]`` makes a driver behave as many real drivers do (usb_cam,
a serial driver that cannot open its port): when its device cannot be reached within SECONDS
(default 1) of its start (off, absent), or the connection to it is lost, it logs why and exits
1. By default a driver waits for its device as long as it runs and, once it lost it, stays up
publishing nothing until it is restarted (the shipped models' behaviour). Ignored by
``--managed`` in ROS 2 mode (a lifecycle node opens its device on its configure transition).

It logs to stderr, runs until SIGTERM or SIGINT and then exits 0. The signals are heard on a
thread of their own (``emulator.stopsignals``, as ``dxboard run`` hears them), never through
the loop's self-pipe that messages could fill; a second one, or a stop still running 9 s
after the first, ends the process at once. A wrong name, directory or
environment is one line on stderr and exit code 2; a device that ``--exit-without-device``
gave up on, exit code 1.
"""

from __future__ import annotations

import asyncio
import contextlib
import json
import logging
import os
import sys
import time
from collections.abc import Sequence
from typing import Any

from emulator.errors import InputError
from emulator.jsonlines import connect_retrying, encode, messages, tcp_address
from emulator.model import EmulatorModelError
from emulator.robot import behaviours as B
from emulator.robot.bus import DEFAULT_ENDPOINT, Bus, TopicBus
from emulator.robot.config import MIDDLEWARES, NodeSpec, load_node
from emulator.robot.driver_status import PERIOD_S, DriverStatus
from emulator.stopsignals import StopSignals

log = logging.getLogger("emulator.robot.node")

RETRY_S = 0.5
EXIT_WITHOUT_DEVICE = "--exit-without-device"
NO_DEVICE_S = 1.0  # --exit-without-device's default wait for the device


class NodeError(InputError):
    """The node cannot start; the message says what to fix."""


class NoDevice(Exception):
    """A driver with ``--exit-without-device`` could not reach its device in time."""


def device_address(spec: NodeSpec, env: dict[str, str]) -> tuple[str, tuple[str, int]]:
    """A driver's device and its (host, port) from ``DXBOARD_DEVICES``."""
    if not spec.hardware:
        raise NodeError(f"{spec.name} is a driver without hardware in system.yaml")
    device = spec.hardware[0]
    raw = env.get("DXBOARD_DEVICES")
    if not raw:
        raise NodeError("DXBOARD_DEVICES is not set: give the device URLs that "
                        "`dxboard emulate SYSTEM_DIR --robot` printed, as a JSON object")
    try:
        urls = json.loads(raw)
    except ValueError:
        urls = None
    if not isinstance(urls, dict):
        raise NodeError(f"DXBOARD_DEVICES is not a JSON object: {raw!r}")
    url = urls.get(device)
    if not isinstance(url, str):
        raise NodeError(f"DXBOARD_DEVICES has no URL for device {device!r}")
    address = tcp_address(url)
    if address is None:
        raise NodeError(f"DXBOARD_DEVICES: {device}: {url!r} is not tcp://HOST:PORT")
    return device, address


async def run_driver(spec: NodeSpec, bus: TopicBus, device: str, address: tuple[str, int],
                     stop: asyncio.Event, give_up_s: float | None = None) -> None:
    """Drive ``device`` until ``stop``; with ``give_up_s``, raise ``NoDevice`` when the first
    connection has not succeeded within that many seconds, or the connection is lost."""
    topics = list(spec.publishes)
    if len(topics) != 1:
        raise NodeError(f"{spec.name}: a driver publishes exactly one topic, not {topics}")
    status = DriverStatus(spec.name, device) if getattr(bus, "ros", False) else None
    reporting = asyncio.ensure_future(_report(bus, status, stop)) if status else None
    try:
        await _drive(spec, bus, topics[0], device, address, stop, status, give_up_s)
    finally:
        if reporting is not None:
            reporting.cancel()
            with contextlib.suppress(asyncio.CancelledError):
                await reporting


async def _report(bus: TopicBus, status: DriverStatus, stop: asyncio.Event) -> None:
    """ROS 2 mode: the driver's ``/diagnostics`` once a second."""
    while not stop.is_set():
        bus.publish("/diagnostics", status.report(time.monotonic()))
        with contextlib.suppress(TimeoutError):
            await asyncio.wait_for(stop.wait(), PERIOD_S)


async def _drive(spec: NodeSpec, bus: TopicBus, topic: str, device: str,
                 address: tuple[str, int], stop: asyncio.Event,
                 status: DriverStatus | None, give_up_s: float | None = None) -> None:
    waited = False

    def refused(exc: OSError) -> None:
        nonlocal waited
        if not waited:
            log.info("%s at %s:%d refuses (%s); waiting for it", device, *address,
                     exc.strerror or exc)
        waited = True

    deadline = None if give_up_s is None else asyncio.get_running_loop().time() + give_up_s
    try:
        pair = await connect_retrying(address, RETRY_S, deadline=deadline, stop=stop,
                                      refused=refused)
    except OSError as exc:  # only with a deadline: --exit-without-device
        raise NoDevice(f"{device} at {address[0]}:{address[1]} unreachable for "
                       f"{give_up_s:g} s ({exc.strerror or exc}); exiting") from None
    if pair is None:
        return
    reader, writer = pair
    log.info("connected to %s at %s:%d; publishing %s", device, *address, topic)
    connected = True
    if status is not None:
        status.connected = True

    def command(in_topic: str, values: dict[str, Any]) -> None:
        cmd = B.device_command(in_topic, values)
        if cmd is None or not connected or writer.is_closing():
            return
        writer.write(encode(cmd))

    for in_topic in spec.subscribes:
        if in_topic not in B.COMMANDS:
            log.warning("%s: no device command for %s; ignoring it", spec.name, in_topic)
        bus.subscribe(in_topic, command)
    reading = asyncio.ensure_future(read_frames(reader, bus.publish, topic, status))
    stopping = asyncio.ensure_future(stop.wait())
    await asyncio.wait([reading, stopping], return_when=asyncio.FIRST_COMPLETED)
    connected = False
    if status is not None:
        status.connected = False
    lost = reading.result() if reading.done() else None
    if lost is not None and give_up_s is None:
        log.warning("lost the connection to %s (%s); publishing nothing until restarted",
                    device, lost)
        await stopping
    stopping.cancel()
    reading.cancel()
    with contextlib.suppress(asyncio.CancelledError):
        await reading
    writer.transport.abort()
    if lost is not None and give_up_s is not None and not stop.is_set():
        raise NoDevice(f"lost the connection to {device} ({lost}); exiting")


async def read_frames(reader: asyncio.StreamReader, publish: B.Publish, topic: str,
                      status: DriverStatus | None = None) -> str:
    """Publish every frame until the connection ends; returns why it ended."""
    try:
        async for frame in messages(reader):
            if "error" in frame:
                log.warning("device says: %s", frame["error"])
                continue
            publish(topic, frame)
            if status is not None:
                status.frame(time.monotonic())
    except asyncio.IncompleteReadError:
        return "closed by the device"
    except asyncio.LimitOverrunError:
        return "line too long"
    except ConnectionError as exc:
        return str(exc) or type(exc).__name__
    return "closed by the device"


async def run_node(spec: NodeSpec, bus: TopicBus, stop: asyncio.Event) -> None:
    def publish(topic: str, values: dict[str, Any]) -> None:
        # the publisher's stamp (host.observers.payload): observers judge the rate by it
        bus.publish(topic, {**values, "stamp": round(time.monotonic(), 6)})

    behaviour = B.make(spec, publish)
    for topic in spec.subscribes:
        bus.subscribe(topic, lambda t, v: behaviour.on_message(t, v, time.monotonic()))
    log.info("running: %s -> %s", ", ".join(spec.subscribes) or "-",
             ", ".join(spec.publishes) or "-")
    next_tick = time.monotonic() + behaviour.tick_s
    while not stop.is_set():
        with contextlib.suppress(TimeoutError):
            await asyncio.wait_for(stop.wait(), max(0.0, next_tick - time.monotonic()))
        now = time.monotonic()
        if now >= next_tick:
            behaviour.tick(now)
            next_tick += behaviour.tick_s
            if next_tick < now:
                next_tick = now + behaviour.tick_s


def middleware(spec: NodeSpec, env: dict[str, str]) -> str:
    """zenoh or ros2: the robot's setting, or ``$DXBOARD_MIDDLEWARE``."""
    chosen = env.get("DXBOARD_MIDDLEWARE") or spec.middleware
    if chosen not in MIDDLEWARES:
        raise NodeError(f"DXBOARD_MIDDLEWARE={chosen!r}: use one of {', '.join(MIDDLEWARES)}")
    return chosen


def open_bus(spec: NodeSpec, env: dict[str, str]) -> TopicBus:
    """The node's bus: a zenoh peer, or a ROS 2 node (the robot's setting or the override)."""
    if middleware(spec, env) == "ros2":
        from emulator.robot.ros_bus import RosBus
        log.info("ROS 2 node %s on domain %s", spec.name, env.get("ROS_DOMAIN_ID", "0"))
        return RosBus(spec.name)
    endpoint = env.get("DXBOARD_ZENOH") or DEFAULT_ENDPOINT
    auth = env.get("DXBOARD_ZENOH_AUTH") or None
    try:
        bus = Bus(endpoint, auth=auth)
    except OSError as exc:
        raise NodeError(f"DXBOARD_ZENOH_AUTH={auth!r}: {exc.strerror}") from None
    except Exception as exc:  # zenoh.ZError: a malformed endpoint
        raise NodeError(f"DXBOARD_ZENOH={endpoint!r}: {exc}") from None
    log.info("zenoh peer connecting to %s", endpoint)
    return bus


async def run_managed(spec: NodeSpec, device: str, address: tuple[str, int],
                      stop: asyncio.Event) -> None:
    """ROS 2 mode with ``--managed``: the driver as a lifecycle node (``managed``)."""
    from emulator.robot.managed import ManagedDriver
    topics = list(spec.publishes)
    if len(topics) != 1:
        raise NodeError(f"{spec.name}: a driver publishes exactly one topic, not {topics}")
    status = DriverStatus(spec.name, device)
    driver = ManagedDriver(spec.name, topics[0], device, address, spec.subscribes, status,
                           asyncio.get_running_loop(), read_frames)
    log.info("ROS 2 managed node %s", spec.name)
    reporting = asyncio.ensure_future(_report(driver.bus, status, stop))
    try:
        await driver.run(stop)
    finally:
        reporting.cancel()
        with contextlib.suppress(asyncio.CancelledError):
            await reporting
        driver.close()


async def main_async(spec: NodeSpec, env: dict[str, str], managed: bool = False,
                     give_up_s: float | None = None) -> None:
    """Run the node until stopped; ``give_up_s``: ``--exit-without-device`` (drivers)."""
    driver = spec.kind in ("SN", "HN")
    if managed and not driver:
        raise NodeError(f"{spec.name} is not a driver: only drivers are managed nodes")
    if give_up_s is not None and not driver:
        raise NodeError(f"{spec.name} is not a driver: {EXIT_WITHOUT_DEVICE} is for drivers")
    device, address = device_address(spec, env) if driver else ("", ("", 0))
    stop = asyncio.Event()
    # not loop.add_signal_handler: its signal byte shares the loop's self-pipe with every
    # message handed over from the middleware's threads, and a full pipe lost SIGTERM (issue 25)
    signals = StopSignals(asyncio.get_running_loop(), stop.set).install()
    try:
        if managed and middleware(spec, env) == "ros2":
            await run_managed(spec, device, address, stop)
            log.info("stopped")
            return
        bus = open_bus(spec, env)
        try:
            if driver:
                await run_driver(spec, bus, device, address, stop, give_up_s)
            else:
                await run_node(spec, bus, stop)
        finally:
            bus.close()
        log.info("stopped")
    finally:
        signals.done()
        signals.close()


def exit_without_device(args: list[str]) -> tuple[float | None, list[str]]:
    """``--exit-without-device[=SECONDS]``'s wait (None: not given) and the other arguments."""
    give_up: float | None = None
    rest = []
    for a in args:
        if a == EXIT_WITHOUT_DEVICE:
            give_up = NO_DEVICE_S
        elif a.startswith(EXIT_WITHOUT_DEVICE + "="):
            raw = a.split("=", 1)[1]
            try:
                give_up = float(raw)
            except ValueError:
                give_up = -1.0
            if not give_up >= 0.0 or give_up == float("inf"):
                raise NodeError(f"{EXIT_WITHOUT_DEVICE}={raw}: give a number of seconds >= 0")
        else:
            rest.append(a)
    return give_up, rest


def main(argv: Sequence[str] | None = None) -> int:
    args = list(sys.argv[1:] if argv is None else argv)
    managed = "--managed" in args
    args = [a for a in args if a != "--managed"]
    try:
        give_up, args = exit_without_device(args)
    except NodeError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    if len(args) == 1 and os.environ.get("DXBOARD_ROBOT"):
        args.append(os.environ["DXBOARD_ROBOT"])
    if len(args) != 2 or args[0].startswith("-"):
        print("usage: python -m emulator.robot.node NAME [SYSTEM_DIR] [--managed] "
              f"[{EXIT_WITHOUT_DEVICE}[=SECONDS]] (SYSTEM_DIR defaults to $DXBOARD_ROBOT)",
              file=sys.stderr)
        return 2
    name, system_dir = args
    logging.basicConfig(stream=sys.stderr, level=logging.INFO,
                        format=f"%(asctime)s {name}[%(process)d] %(levelname)s %(message)s")
    try:
        spec = load_node(system_dir, name)
        asyncio.run(main_async(spec, dict(os.environ), managed, give_up))
    except (EmulatorModelError, NodeError) as exc:
        print(f"{name}: error: {exc}", file=sys.stderr)
        return 2
    except NoDevice as exc:
        log.error("%s", exc)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
