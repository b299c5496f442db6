"""A node of the virtual robot as an OS process: ``python -m emulator.robot.node NAME [DIR]``.

``NAME`` is a node component (N, HN or SN) of ``DIR/system.yaml``; what it does is in
``emulator.robot.behaviours``. The environment gives the rest:

    DXBOARD_ROBOT    the robot directory when DIR is not given (the daemon sets it for every
                     process it starts)
    DXBOARD_ZENOH    the zenoh endpoint to connect to (default tcp/127.0.0.1:7447: the daemon)
    DXBOARD_DEVICES  drivers only: a JSON object device name -> tcp://HOST:PORT, as
                     ``dxboard emulate SYSTEM_DIR --robot`` prints them

It logs to stderr, runs until SIGTERM or SIGINT and then exits 0. A wrong name, directory or
environment is one line on stderr and exit code 2.
"""

from __future__ import annotations

import asyncio
import contextlib
import json
import logging
import os
import signal
import sys
import time
from collections.abc import Sequence
from typing import Any
from urllib.parse import urlsplit

from emulator.errors import InputError
from emulator.model import EmulatorModelError
from emulator.robot import behaviours as B
from emulator.robot.bus import DEFAULT_ENDPOINT, Bus
from emulator.robot.config import NodeSpec, load_node

log = logging.getLogger("emulator.robot.node")

RETRY_S = 0.5
MAX_LINE = 65536


class NodeError(InputError):
    """The node cannot start; the message says what to fix."""


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
    parts = urlsplit(url)
    try:
        port = parts.port
    except ValueError:
        port = None
    if parts.scheme != "tcp" or not parts.hostname or port is None:
        raise NodeError(f"DXBOARD_DEVICES: {device}: {url!r} is not tcp://HOST:PORT")
    return device, (parts.hostname, port)


async def run_driver(spec: NodeSpec, bus: Bus, device: str, address: tuple[str, int],
                     stop: asyncio.Event) -> None:
    topics = list(spec.publishes)
    if len(topics) != 1:
        raise NodeError(f"{spec.name}: a driver publishes exactly one topic, not {topics}")
    topic = topics[0]
    reader: asyncio.StreamReader | None = None
    writer: asyncio.StreamWriter | None = None
    waited = False
    while not stop.is_set():
        try:
            reader, writer = await asyncio.open_connection(*address, limit=MAX_LINE)
            break
        except OSError as exc:
            if not waited:
                log.info("%s at %s:%d refuses (%s); waiting for it", device, *address,
                         exc.strerror or exc)
                waited = True
            with contextlib.suppress(TimeoutError):
                await asyncio.wait_for(stop.wait(), RETRY_S)
    if reader is None or writer is None:
        return
    log.info("connected to %s at %s:%d; publishing %s", device, *address, topic)
    connected = True

    def command(in_topic: str, values: dict[str, Any]) -> None:
        cmd = B.device_command(in_topic, values)
        if cmd is None or not connected or writer.is_closing():
            return
        writer.write(json.dumps(cmd, separators=(",", ":")).encode() + b"\n")

    for in_topic in spec.subscribes:
        if in_topic not in B.COMMANDS:
            log.warning("%s: no device command for %s; ignoring it", spec.name, in_topic)
        bus.subscribe(in_topic, command)
    reading = asyncio.ensure_future(_read(reader, bus, topic))
    stopping = asyncio.ensure_future(stop.wait())
    await asyncio.wait([reading, stopping], return_when=asyncio.FIRST_COMPLETED)
    connected = False
    if reading.done():
        log.warning("lost the connection to %s (%s); publishing nothing until restarted",
                    device, reading.result())
        await stopping
    reading.cancel()
    with contextlib.suppress(asyncio.CancelledError):
        await reading
    writer.transport.abort()


async def _read(reader: asyncio.StreamReader, bus: Bus, topic: str) -> str:
    """Publish every frame until the connection ends; returns why it ended."""
    while True:
        try:
            line = await reader.readuntil(b"\n")
        except asyncio.IncompleteReadError:
            return "closed by the device"
        except asyncio.LimitOverrunError:
            return "line too long"
        except ConnectionError as exc:
            return str(exc) or type(exc).__name__
        try:
            frame = json.loads(line)
        except (ValueError, UnicodeDecodeError):
            log.warning("not a JSON line from the device: %r", line[:80])
            continue
        if isinstance(frame, dict) and "error" not in frame:
            bus.publish(topic, frame)
        elif isinstance(frame, dict):
            log.warning("device says: %s", frame["error"])


async def run_node(spec: NodeSpec, bus: Bus, stop: asyncio.Event) -> None:
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


async def main_async(spec: NodeSpec, env: dict[str, str]) -> None:
    driver = spec.kind in ("SN", "HN")
    device, address = device_address(spec, env) if driver else ("", ("", 0))
    loop = asyncio.get_running_loop()
    stop = asyncio.Event()
    for sig in (signal.SIGTERM, signal.SIGINT):
        loop.add_signal_handler(sig, stop.set)
    endpoint = env.get("DXBOARD_ZENOH") or DEFAULT_ENDPOINT
    try:
        bus = Bus(endpoint)
    except Exception as exc:  # zenoh.ZError: a malformed endpoint
        raise NodeError(f"DXBOARD_ZENOH={endpoint!r}: {exc}") from None
    log.info("zenoh peer connecting to %s", endpoint)
    try:
        if driver:
            await run_driver(spec, bus, device, address, stop)
        else:
            await run_node(spec, bus, stop)
    finally:
        bus.close()
    log.info("stopped")


def main(argv: Sequence[str] | None = None) -> int:
    args = list(sys.argv[1:] if argv is None else argv)
    if len(args) == 1 and os.environ.get("DXBOARD_ROBOT"):
        args.append(os.environ["DXBOARD_ROBOT"])
    if len(args) != 2 or args[0].startswith("-"):
        print("usage: python -m emulator.robot.node NAME SYSTEM_DIR (or $DXBOARD_ROBOT)",
              file=sys.stderr)
        return 2
    name, system_dir = args
    logging.basicConfig(stream=sys.stderr, level=logging.INFO,
                        format=f"%(asctime)s {name}[%(process)d] %(levelname)s %(message)s")
    try:
        spec = load_node(system_dir, name)
        asyncio.run(main_async(spec, dict(os.environ)))
    except (EmulatorModelError, NodeError) as exc:
        print(f"{name}: error: {exc}", file=sys.stderr)
        return 2
    return 0


if __name__ == "__main__":
    sys.exit(main())
