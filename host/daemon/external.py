"""The daemon's actuators for nodes started elsewhere (``external:`` of ``system.yaml``).

``ExternalActuators(external, kind, domain)`` registers, with the repair executor's
``Actuators``, ``restart_node`` (``host.repair.restart``: the node's systemd unit, command or
container) and, on ROS 2 for the nodes with ``lifecycle: true``, ``activate_node`` and
``reset_node`` through a ``host.ros.manager.LifecycleManager`` on a ROS 2 node of its own
(``dxboard_lifecycle_manager``), which also watches each node's transition events (logged:
whoever changes a node's state, the daemon's log says so). ``close()`` is idempotent.
``check_external(file, external, kind)`` is the load-time rule: lifecycle needs ROS 2.
"""

from __future__ import annotations

import logging
from collections.abc import Mapping
from pathlib import Path
from typing import Any

from host.errors import UserError
from host.repair.actuators import Actuators
from host.repair.external import ExternalNode, lifecycle_nodes
from host.repair.restart import RestartActuator

log = logging.getLogger(__name__)


def check_external(file: Path, external: Mapping[str, ExternalNode], kind: str) -> None:
    """Managed (lifecycle) nodes exist on ROS 2 only: a UserError on another middleware."""
    managed = lifecycle_nodes(external)
    if managed and kind != "ros2":
        raise UserError(f"{file}: external: {', '.join(managed)} have lifecycle: true, but the "
                        f"robot's topics are on {kind}",
                        "run it with --middleware ros2, or drop lifecycle: true")


class ExternalActuators:
    def __init__(self, external: Mapping[str, ExternalNode], kind: str,
                 domain: int | None = None) -> None:
        self.external = dict(external)
        self.kind = kind
        self.domain = domain
        self._ros: Any = None

    def open(self, actuators: Actuators) -> None:
        if not self.external:
            return
        actuators.add("restart_node", RestartActuator(self.external).restart_node)
        managed = lifecycle_nodes(self.external)
        if self.kind != "ros2" or not managed or self._ros is not None:
            return
        from host.observers.sources.ros2_node import RosNode
        from host.ros.manager import LifecycleManager

        self._ros = RosNode("dxboard_lifecycle_manager", self.domain)
        manager = LifecycleManager(self._ros)
        actuators.add("activate_node", manager.activate)
        actuators.add("reset_node", manager.reset)
        for node in managed:
            manager.watch(node, lambda n, s: log.info("%s is %s (transition event)", n, s))

    def close(self) -> None:
        if self._ros is not None:
            self._ros.close()
            self._ros = None
