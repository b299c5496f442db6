"""How the second robot's plain rclpy scripts run their node: spin until SIGINT/SIGTERM, then
shut down cleanly (what every rclpy ``main`` does; no dxboard code)."""

from __future__ import annotations

from typing import Any

import rclpy
from rclpy.executors import ExternalShutdownException


def spin(node: Any) -> None:
    try:
        rclpy.spin(node)
    except (KeyboardInterrupt, ExternalShutdownException):
        pass
    finally:
        node.destroy_node()
        rclpy.try_shutdown()
