"""A camera-like ROS 2 publisher: plain rclpy, no dxboard.

``python camera.py NAME TOPIC [--rate HZ] [--pidfile FILE]`` publishes small
``sensor_msgs/Image`` frames (8x8 mono8) on TOPIC at HZ (default 9) as node NAME, until
SIGTERM. With ``--pidfile`` it writes its pid there (what a launcher keeps to restart it).
"""

from __future__ import annotations

import argparse
import os

import rclpy
from rclpy.node import Node
from sensor_msgs.msg import Image
from spin import spin  # beside this script (its sys.path[0])


def main() -> None:
    p = argparse.ArgumentParser()
    p.add_argument("name")
    p.add_argument("topic")
    p.add_argument("--rate", type=float, default=9.0)
    p.add_argument("--pidfile")
    a = p.parse_args()
    if a.pidfile:
        with open(a.pidfile, "w") as f:
            f.write(str(os.getpid()))
    rclpy.init()
    node = Node(a.name)
    pub = node.create_publisher(Image, a.topic, 10)
    frame = Image(height=8, width=8, encoding="mono8", step=8, data=bytes(64))

    def tick() -> None:
        frame.header.stamp = node.get_clock().now().to_msg()
        pub.publish(frame)

    node.create_timer(1.0 / a.rate, tick)
    spin(node)


if __name__ == "__main__":
    main()
