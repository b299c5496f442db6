"""A plain rclpy node that republishes what it hears: ``python relay.py NAME IN OUT``.

Subscribes ``sensor_msgs/Image`` on IN and publishes each message again on OUT at once (an
image pipeline's stage: its output follows its input in time). No dxboard code.
"""

from __future__ import annotations

import sys

import rclpy
from rclpy.node import Node
from sensor_msgs.msg import Image
from spin import spin  # beside this script (its sys.path[0])


def main() -> None:
    name, inp, out = sys.argv[1:4]
    rclpy.init()
    node = Node(name)
    pub = node.create_publisher(Image, out, 10)
    node.create_subscription(Image, inp, pub.publish, 10)
    spin(node)


if __name__ == "__main__":
    main()
