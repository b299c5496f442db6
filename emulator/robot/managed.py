"""A driver as a ROS 2 managed (lifecycle) node, as the ROS 2 Hokuyo driver (urg_node) is.

``python -m emulator.robot.node hokuyo_node DIR --managed`` in ROS 2 mode makes the driver an
rclpy ``LifecycleNode`` whose transitions are its device connection::

    transition   what the driver does                                     fails when
    configure    connects to its device (tries every CONNECT_RETRY_S      the device refuses
                 for CONNECT_S: it may still be off, a power cycle's       for CONNECT_S
                 off time not yet over on the board)
    activate     publishes what the device sends
    deactivate   stops publishing (stays connected)
    cleanup      closes the connection                                    -
    shutdown     closes the connection                                    -

Like ``ros2 launch ... autostart:=true``, the node configures itself at start (again every
RETRY_S until the device answers: it may not be powered yet) and activates. When the
connection drops (the device lost power) it stays *active* but publishes nothing, as the plain
driver does; a lifecycle repair (deactivate, cleanup, configure, activate, through the
standard ``/NODE/change_state`` service) reconnects it without restarting the process.

Transition callbacks run on rclpy's executor thread; each one runs its coroutine on the node
program's asyncio loop (``run_coroutine_threadsafe``) and waits for it there, so the
connection and the reading task live on the loop as in the plain driver. Frames are published
only while active; ``/diagnostics`` (``driver_status``) goes on in every state.
"""

from __future__ import annotations

import asyncio
import contextlib
import logging
from collections.abc import Callable, Coroutine
from typing import Any

import rclpy
from rclpy.context import Context
from rclpy.lifecycle import LifecycleNode, LifecycleState, TransitionCallbackReturn
from rclpy.signals import SignalHandlerOptions

from emulator.jsonlines import connect_retrying, encode
from emulator.robot import behaviours as B
from emulator.robot.driver_status import DriverStatus
from emulator.robot.ros_bus import RosBus

log = logging.getLogger("emulator.robot.managed")

CONNECT_S = 5.0  # configure: how long to try the device (a power cycle's off time, and more)
CONNECT_RETRY_S = 0.05  # a refused local connection is cheap to try again: no time lost
RETRY_S = 0.5  # autostart: configure again after a failed one
CALLBACK_S = 10.0  # a transition's coroutine must finish within this

Publish = Callable[[str, dict[str, Any]], None]
ReadFrames = Callable[[asyncio.StreamReader, Publish, str, DriverStatus | None],
                      Coroutine[Any, Any, str]]


class _Node(LifecycleNode):
    def __init__(self, name: str, driver: ManagedDriver, context: Context) -> None:
        self.driver = driver
        super().__init__(name, context=context)

    def on_configure(self, state: LifecycleState) -> TransitionCallbackReturn:
        return self.driver.transition(self.driver.configure())

    def on_activate(self, state: LifecycleState) -> TransitionCallbackReturn:
        self.driver.active = True
        log.info("active: publishing %s", self.driver.topic)
        return TransitionCallbackReturn.SUCCESS

    def on_deactivate(self, state: LifecycleState) -> TransitionCallbackReturn:
        self.driver.active = False
        log.info("inactive")
        return TransitionCallbackReturn.SUCCESS

    def on_cleanup(self, state: LifecycleState) -> TransitionCallbackReturn:
        return self.driver.transition(self.driver.disconnect())

    def on_shutdown(self, state: LifecycleState) -> TransitionCallbackReturn:
        self.driver.active = False
        return self.driver.transition(self.driver.disconnect())


class ManagedDriver:
    def __init__(self, name: str, topic: str, device: str, address: tuple[str, int],
                 subscribes: tuple[str, ...], status: DriverStatus,
                 loop: asyncio.AbstractEventLoop, read_frames: ReadFrames) -> None:
        self.read_frames = read_frames  # the plain driver's reader (emulator.robot.node)
        self.topic = topic
        self.device = device
        self.address = address
        self.status = status
        self.loop = loop
        self.active = False
        self._writer: asyncio.StreamWriter | None = None
        self._reading: asyncio.Task[str] | None = None
        context = Context()
        rclpy.init(context=context, signal_handler_options=SignalHandlerOptions.NO)
        self.node = _Node(name, self, context)
        self.bus = RosBus(name, self.node, context)
        for in_topic in subscribes:
            self.bus.subscribe(in_topic, self._command)

    # -- transitions (their coroutines run on the loop) ---------------------------------------
    def transition(self, coro: Any) -> TransitionCallbackReturn:
        """Run ``coro`` on the loop, from the executor's thread; SUCCESS iff it returns True."""
        try:
            ok = asyncio.run_coroutine_threadsafe(coro, self.loop).result(CALLBACK_S)
        except Exception as exc:
            log.warning("transition failed: %s", exc)
            ok = False
        return TransitionCallbackReturn.SUCCESS if ok else TransitionCallbackReturn.FAILURE

    async def configure(self) -> bool:
        await self.disconnect()
        try:
            pair = await connect_retrying(self.address, CONNECT_RETRY_S,
                                          deadline=self.loop.time() + CONNECT_S)
        except OSError as exc:
            log.info("configure: %s at %s:%d refuses (%s)", self.device, *self.address,
                     exc.strerror or exc)
            return False
        assert pair is not None  # no stop event: connected or raised
        reader, self._writer = pair
        self.status.connected = True
        self._reading = asyncio.ensure_future(
            self.read_frames(reader, self._publish, self.topic, self.status))
        self._reading.add_done_callback(self._lost)
        log.info("configured: connected to %s at %s:%d", self.device, *self.address)
        return True

    async def disconnect(self) -> bool:
        if self._reading is not None:
            self._reading.remove_done_callback(self._lost)
            self._reading.cancel()
            with contextlib.suppress(asyncio.CancelledError):
                await self._reading
            self._reading = None
        if self._writer is not None:
            self._writer.transport.abort()
            self._writer = None
        self.status.connected = False
        return True

    def _lost(self, task: asyncio.Task[str]) -> None:
        self.status.connected = False
        if not task.cancelled():
            log.warning("lost the connection to %s (%s); publishing nothing until "
                        "reconfigured", self.device, task.result())

    def _publish(self, topic: str, values: dict[str, Any]) -> None:
        if self.active:
            self.bus.publish(topic, values)

    def _command(self, in_topic: str, values: dict[str, Any]) -> None:
        cmd = B.device_command(in_topic, values)
        w = self._writer
        if cmd is not None and self.active and w is not None and not w.is_closing():
            w.write(encode(cmd))

    # -- the node's life ---------------------------------------------------------------------
    async def run(self, stop: asyncio.Event) -> None:
        """Autostart (configure until the device answers, then activate), then wait for stop."""
        while not stop.is_set():
            ret = await self.loop.run_in_executor(None, self.node.trigger_configure)
            if ret == TransitionCallbackReturn.SUCCESS:
                await self.loop.run_in_executor(None, self.node.trigger_activate)
                break
            with contextlib.suppress(TimeoutError):
                await asyncio.wait_for(stop.wait(), RETRY_S)
        await stop.wait()
        self.active = False
        await self.disconnect()

    def close(self) -> None:
        self.bus.close()
