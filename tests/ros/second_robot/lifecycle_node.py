"""A standard ROS 2 managed node that waits for a lifecycle manager: plain rclpy, no dxboard.

``python lifecycle_node.py NAME [--topic T] [--configure-delay S] [--rate HZ]`` starts it
unconfigured, as Nav2's nodes and most drivers do, and waits for a manager to configure and
activate it through ``/NAME/change_state``. While active it publishes ``std_msgs/String`` on
T (default ``/NAME/out``) at HZ (default 10). ``--configure-delay`` makes its configure take S
seconds (a driver opening a slow device), longer than a hasty manager waits for the call's answer.
``--device FILE``: configure fails while FILE does not exist (its device is off).
"""

from __future__ import annotations

import argparse
import os
import time
from typing import Any

import rclpy
from rclpy.lifecycle import LifecycleNode, LifecycleState, TransitionCallbackReturn
from spin import spin  # beside this script (its sys.path[0])
from std_msgs.msg import String


class Subject(LifecycleNode):
    def __init__(self, name: str, topic: str, delay: float, rate: float,
                 device: str | None) -> None:
        super().__init__(name)
        self.delay, self.rate, self.device = delay, rate, device
        self.pub = self.create_lifecycle_publisher(String, topic, 10)
        self.timer: Any = None
        self.count = 0

    def on_configure(self, state: LifecycleState) -> TransitionCallbackReturn:
        time.sleep(self.delay)
        if self.device is not None and not os.path.exists(self.device):
            self.get_logger().error(f"device {self.device} is off")
            return TransitionCallbackReturn.FAILURE
        self.timer = self.create_timer(1.0 / self.rate, self.tick)
        return TransitionCallbackReturn.SUCCESS

    def tick(self) -> None:
        self.count += 1
        msg = String()
        msg.data = str(self.count)
        self.pub.publish(msg)  # a lifecycle publisher sends only while active

    def on_cleanup(self, state: LifecycleState) -> TransitionCallbackReturn:
        if self.timer is not None:
            self.destroy_timer(self.timer)
            self.timer = None
        return TransitionCallbackReturn.SUCCESS


def main() -> None:
    p = argparse.ArgumentParser()
    p.add_argument("name")
    p.add_argument("--topic")
    p.add_argument("--configure-delay", type=float, default=0.0)
    p.add_argument("--rate", type=float, default=10.0)
    p.add_argument("--device")
    a = p.parse_args()
    rclpy.init()
    node = Subject(a.name, a.topic or f"/{a.name}/out", a.configure_delay, a.rate, a.device)
    spin(node)


if __name__ == "__main__":
    main()
