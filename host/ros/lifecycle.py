"""Lifecycle repairs: drive a ROS 2 managed node through the standard lifecycle services.

A managed node (``rclpy.lifecycle``, ``rclcpp_lifecycle``) offers ``/NODE/get_state``
(``lifecycle_msgs/srv/GetState``) and ``/NODE/change_state`` (``ChangeState``).
``LifecycleClient(ros)`` calls them from the daemon's asyncio loop through a ``RosNode``
(``host.ros.node``: rclpy's futures complete on its thread and are handed to the loop).
``reconfigure(node)`` is the repair of a driver whose device was power-cycled: from wherever
the node is, the shortest way back to *active* through a fresh connection::

    active        deactivate, cleanup, configure, activate
    inactive      cleanup, configure, activate
    unconfigured  configure, activate

A refused transition, a missing service or a node that is not *active* at the end raises
``LifecycleError`` naming the node, the transition and the state it was left in; the caller
(the repair executor) verifies the effect by the node's topics as for any repair.

``LifecycleActuator(domain_id)`` is the repair domain's ``reconfigure_node(n)`` for the
executor's ``Actuators``: its own ROS 2 node (``dxboard_lifecycle``), made at the first repair.
"""

from __future__ import annotations

import asyncio
import logging
from typing import Any

from lifecycle_msgs.msg import Transition
from lifecycle_msgs.srv import ChangeState, GetState

from host.errors import RemoteError
from host.ros.node import RosNode

log = logging.getLogger(__name__)

TIMEOUT_S = 10.0
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

    async def _call(self, srv: Any, node: str, name: str, request: Any) -> Any:
        client = self._client(srv, node, name)
        loop = asyncio.get_running_loop()
        try:
            async with asyncio.timeout(self.timeout_s):
                while not client.service_is_ready():
                    await asyncio.sleep(0.05)
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
    def __init__(self, domain_id: int | None = None, timeout_s: float = TIMEOUT_S) -> None:
        self.domain_id = domain_id
        self.timeout_s = timeout_s
        self._ros: RosNode | None = None
        self._client: LifecycleClient | None = None

    async def reconfigure_node(self, node: str) -> str:
        if self._client is None:
            self._ros = RosNode("dxboard_lifecycle", self.domain_id)
            self._client = LifecycleClient(self._ros, self.timeout_s)
        steps = await self._client.reconfigure(node)
        return f"{node} {', '.join(steps)}: active"

    def close(self) -> None:
        if self._ros is not None:
            self._ros.close()
            self._ros = None
            self._client = None
