"""Lifecycle repairs: drive a ROS 2 managed node through the standard lifecycle services.

A managed node (``rclpy.lifecycle``, ``rclcpp_lifecycle``) offers ``/NODE/get_state``
(``lifecycle_msgs/srv/GetState``) and ``/NODE/change_state`` (``ChangeState``).
``LifecycleClient(ros)`` calls them from the daemon's asyncio loop through a ``RosNode``
(``sources.ros2_node``: rclpy's futures complete on its thread and are handed to the loop).
``reconfigure(node)`` is the repair of a driver whose device was power-cycled: from wherever
the node is, the shortest way back to *active* through a fresh connection::

    active        deactivate, cleanup, configure, activate
    inactive      cleanup, configure, activate
    unconfigured  configure, activate

A refused transition, a missing service or a node that is not *active* at the end raises
``LifecycleError`` naming the node, the transition and the state it was left in; the caller
(the repair executor) verifies the effect by the node's topics as for any repair.

``LifecycleActuator(domain_id, nodes)`` is the repair domain's ``reconfigure_node(n)`` for the
executor's ``Actuators``: its own ROS 2 node (``dxboard_lifecycle``), made when the daemon
starts, not at the first repair. ``open()`` (on the daemon's loop) also makes the service
clients of every managed node in ``nodes`` and waits, in the background, for the node's
services to be discovered and answer once (``LifecycleClient.warm``): when the node is first
seen, not when it is first repaired. Made at the first repair instead, the lifecycle node, its
discovery of the managed node's services and the first calls came on top of the repair
(1.5-2.9 s in the ROS 2 hang runs of issue 18) and stalled the daemon's other rclpy nodes.
The step's detail says how long it waited for the services and how long the transitions took.
"""

from __future__ import annotations

import asyncio
import logging
import time
from collections.abc import Callable, Iterable
from typing import Any

from lifecycle_msgs.msg import Transition
from lifecycle_msgs.srv import ChangeState, GetState

from host.errors import RemoteError
from host.observers.sources.ros2_node import RosNode

log = logging.getLogger(__name__)

TIMEOUT_S = 10.0
POLL_S = 0.05  # how often a service not yet discovered is looked for
STEPS = {
    "active": ("deactivate", "cleanup", "configure", "activate"),
    "inactive": ("cleanup", "configure", "activate"),
    "unconfigured": ("configure", "activate"),
}
TRANSITIONS = {"configure": Transition.TRANSITION_CONFIGURE,
               "cleanup": Transition.TRANSITION_CLEANUP,
               "activate": Transition.TRANSITION_ACTIVATE,
               "deactivate": Transition.TRANSITION_DEACTIVATE}


class LifecycleError(RemoteError):
    """A managed node did not reach the state asked for; the message says where it stopped."""


class LifecycleClient:
    def __init__(self, ros: RosNode, timeout_s: float = TIMEOUT_S) -> None:
        self.ros = ros
        self.timeout_s = timeout_s
        self._clients: dict[tuple[str, str], Any] = {}

    def _client(self, srv: Any, node: str, name: str) -> Any:
        key = (node, name)
        if key not in self._clients:
            self._clients[key] = self.ros.node.create_client(srv, f"/{node}/{name}")
        return self._clients[key]

    def _services(self, node: str) -> list[Any]:
        return [self._client(GetState, node, "get_state"),
                self._client(ChangeState, node, "change_state")]

    async def discovered(self, node: str, timeout_s: float | None = None) -> bool:
        """Return once ``node``'s lifecycle services are discovered (``timeout_s`` None: no
        time limit; else ``LifecycleError`` after it): True if they were already."""
        clients = self._services(node)
        already = True
        try:
            async with asyncio.timeout(timeout_s):
                while not all(c.service_is_ready() for c in clients):
                    already = False
                    await asyncio.sleep(POLL_S)
                return already
        except TimeoutError:
            raise LifecycleError(f"{node}: no lifecycle services /{node}/get_state and "
                                 f"/{node}/change_state within {timeout_s:g} s",
                                 "is it a managed (lifecycle) node, and running?") from None

    async def warm(self, node: str) -> str:
        """Make ``node``'s service clients now, wait until its services are discovered and
        ask its state once (the first call of a client may wait on its reply path): so that
        a repair finds them ready. No time limit: the node may be started much later.
        Returns the node's state."""
        await self.discovered(node)
        return await self.state(node)

    async def _call(self, srv: Any, node: str, name: str, request: Any) -> Any:
        client = self._client(srv, node, name)
        loop = asyncio.get_running_loop()
        try:
            async with asyncio.timeout(self.timeout_s):
                while not client.service_is_ready():
                    await asyncio.sleep(POLL_S)
                done: asyncio.Future[Any] = loop.create_future()

                def settle(result: Any) -> None:
                    if not done.done():
                        done.set_result(result)

                def finished(f: Any) -> None:  # on rclpy's thread
                    loop.call_soon_threadsafe(settle, f.result())

                client.call_async(request).add_done_callback(finished)
                return await done
        except TimeoutError:
            raise LifecycleError(f"{node}: no answer from /{node}/{name} within "
                                 f"{self.timeout_s:g} s",
                                 "is it a managed (lifecycle) node, and running?") from None

    async def state(self, node: str) -> str:
        """The node's lifecycle state: unconfigured, inactive, active or finalized."""
        reply = await self._call(GetState, node, "get_state", GetState.Request())
        return str(reply.current_state.label)

    async def change(self, node: str, transition: str) -> None:
        req = ChangeState.Request()
        req.transition.id = TRANSITIONS[transition]
        reply = await self._call(ChangeState, node, "change_state", req)
        if not reply.success:
            raise LifecycleError(f"{node}: transition {transition} failed; the node is "
                                 f"{await self.state(node)}",
                                 "is its device powered and answering?")

    async def reconfigure(self, node: str) -> list[str]:
        """Bring ``node`` back to active through a fresh configure; the transitions made."""
        start = await self.state(node)
        steps = STEPS.get(start)
        if steps is None:
            raise LifecycleError(f"{node} is {start}: it cannot be reconfigured",
                                 "restart its process")
        for step in steps:
            log.info("%s: %s", node, step)
            await self.change(node, step)
        end = await self.state(node)
        if end != "active":
            raise LifecycleError(f"{node} is {end} after {', '.join(steps)}",
                                 "restart its process")
        return list(steps)


class LifecycleActuator:
    def __init__(self, domain_id: int | None = None, nodes: Iterable[str] = (),
                 timeout_s: float = TIMEOUT_S,
                 clock: Callable[[], float] = time.monotonic) -> None:
        self.domain_id = domain_id
        self.nodes = tuple(nodes)
        self.timeout_s = timeout_s
        self.clock = clock
        self._ros: RosNode | None = None
        self._client: LifecycleClient | None = None
        self._warming: list[asyncio.Task[None]] = []
        #: the managed nodes whose services were found and answered (``open``)
        self.warmed: set[str] = set()

    def open(self) -> None:
        """Make the lifecycle node now, and warm the managed nodes' services in the
        background (see the module docstring); idempotent."""
        if self._client is not None:
            return
        self._ros = RosNode("dxboard_lifecycle", self.domain_id)
        self._client = LifecycleClient(self._ros, self.timeout_s)
        loop = asyncio.get_running_loop()
        self._warming = [loop.create_task(self._warm(self._client, n), name=f"warm:{n}")
                         for n in self.nodes]

    async def _warm(self, client: LifecycleClient, node: str) -> None:
        t0 = self.clock()
        try:
            state = await client.warm(node)
        except LifecycleError as exc:  # answers later, or the repair says so
            log.warning("%s's lifecycle services: %s", node, exc)
            return
        self.warmed.add(node)
        log.info("%s's lifecycle services found and answering after %.3f s (%s)", node,
                 self.clock() - t0, state)

    async def reconfigure_node(self, node: str) -> str:
        t0 = self.clock()
        if self._client is None:
            self.open()
        assert self._client is not None
        already = await self._client.discovered(node, self.timeout_s)
        t1 = self.clock()
        steps = await self._client.reconfigure(node)
        found = "already known" if already else f"found in {t1 - t0:.3f} s"
        return (f"{node} {', '.join(steps)}: active (its services {found}, transitions "
                f"{self.clock() - t1:.3f} s)")

    def close(self) -> None:
        for task in self._warming:
            task.cancel()
        self._warming = []
        if self._ros is not None:
            self._ros.close()
            self._ros = None
            self._client = None
