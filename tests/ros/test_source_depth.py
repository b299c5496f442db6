"""The daemon's ROS 2 source loses no message while its executor is held up: a daemon on a busy
machine is descheduled for tenths of a second, and a reader that keeps only the last 10 messages
drops what a 100 Hz topic sent meanwhile — a rate drop the frequency observer then reports
(``~ok(/imu_data)`` flapping under load on `make run`'s ROS 2 robot, where Zenoh's was quiet).

A plain rclpy publisher (reliable, as the virtual robot's nodes are; the source then reads
reliably too, so nothing is lost on the way) sends a burst while the
source's executor is blocked by a callback of its own node; once it is released, every message
of the burst must reach the subscriber.
"""

from __future__ import annotations

import threading

from rclpy.duration import Duration
from rclpy.qos import QoSHistoryPolicy, QoSProfile, QoSReliabilityPolicy
from std_msgs.msg import Int32

from host.observers.payload import TopicMessage
from host.observers.sources.ros2 import Ros2Source
from tests.ros.conftest import Peer
from tests.wait import wait_until_async

BURST = 60  # 0.6 s of a 100 Hz topic


async def test_a_burst_sent_while_the_source_is_held_up_is_received_whole(domain: int) -> None:
    got: list[TopicMessage] = []
    peer = Peer(domain, "burst_publisher")
    source = Ros2Source(domain)  # the type and a reliable reader from the graph
    try:
        pub = peer.node.create_publisher(Int32, "/burst", QoSProfile(
            history=QoSHistoryPolicy.KEEP_LAST, depth=BURST,
            reliability=QoSReliabilityPolicy.RELIABLE))
        source.subscribe("/burst", got.append)
        await wait_until_async(lambda: pub.get_subscription_count() >= 1, 60.0,
                               "the source's subscription matched")
        held, release = threading.Event(), threading.Event()

        def hold() -> None:  # on the source's executor: nothing else runs there meanwhile
            timer.cancel()
            held.set()
            release.wait(60.0)

        timer = source.ros.node.create_timer(0.01, hold)
        await wait_until_async(held.is_set, 60.0, "the source's executor held")
        for i in range(BURST):
            pub.publish(Int32(data=i))
        await wait_until_async(lambda: pub.wait_for_all_acked(Duration(seconds=1)), 60.0,
                               "the burst acknowledged by the source's reader")
        release.set()
        await wait_until_async(lambda: len(got) >= BURST, 30.0, f"{BURST} messages",
                               show=lambda: f"{len(got)} received")
        assert len(got) == BURST
    finally:
        source.close()
        peer.close()
