"""The ROS 2 source delivers a topic's messages only from the node the model says publishes it.

Two real rclpy nodes in the test's own DDS domain publish ``/odom``: ``base_node`` (the model's
publisher, as ``publishes:`` in ``system.yaml`` says) and ``stranger`` (any other participant of
the domain). The source, given ``publishers={"/odom": ["base_node"]}``, hands on every message
of the first and none of the second, and tells of the stranger once (``on_stranger``) however
many messages it sends. A topic the model names no publisher for takes every publisher.
"""

from __future__ import annotations

from std_msgs.msg import Int32

from host.observers.payload import TopicMessage
from host.observers.sources.ros2 import Ros2Source
from host.observers.sources.ros2_message import RosMessage
from tests.ros.conftest import Peer
from tests.wait import wait_until_async

QOS = 100


def value(msg: TopicMessage) -> int:
    assert isinstance(msg, RosMessage)
    values = msg.values
    assert values is not None
    return int(values["data"])


async def test_a_strangers_messages_are_ignored_and_told_once(domain: int) -> None:
    base, stranger = Peer(domain, "base_node"), Peer(domain, "stranger")
    source = Ros2Source(domain, publishers={"/odom": ["base_node"]})
    told: list[tuple[str, str]] = []
    source.on_stranger = lambda topic, node: told.append((topic, node))
    got: list[TopicMessage] = []
    try:
        real = base.node.create_publisher(Int32, "/odom", QOS)
        fake = stranger.node.create_publisher(Int32, "/odom", QOS)
        source.subscribe("/odom", got.append)
        await wait_until_async(lambda: real.get_subscription_count() >= 1
                               and fake.get_subscription_count() >= 1, 60.0,
                               "the source's subscription matched with both publishers")

        def burst() -> None:  # the stranger 10 times as often as the base
            real.publish(Int32(data=1))
            for _ in range(10):
                fake.publish(Int32(data=2))

        await wait_until_async(lambda: told and len(got) >= 5, 60.0,
                               "the stranger told of and the base's messages received",
                               each=burst, show=lambda: (told, len(got)))
        mark = len(got)
        await wait_until_async(lambda: len(got) >= mark + 20, 60.0,
                               "more of the base's messages", each=burst,
                               show=lambda: len(got))
        assert [m for m in got if value(m) != 1] == []  # not one of the stranger's
        assert told == [("/odom", "stranger")]  # once, however many it sent
    finally:
        source.close()
        base.close()
        stranger.close()


async def test_a_topic_without_a_model_publisher_takes_every_publisher(domain: int) -> None:
    stranger = Peer(domain, "stranger")
    source = Ros2Source(domain, publishers={"/odom": ["base_node"]})
    got: list[TopicMessage] = []
    try:
        pub = stranger.node.create_publisher(Int32, "/chatter", QOS)
        source.subscribe("/chatter", got.append)
        await wait_until_async(lambda: pub.get_subscription_count() >= 1, 60.0,
                               "the source's subscription matched")
        await wait_until_async(lambda: len(got) >= 5, 60.0, "the messages",
                               each=lambda: pub.publish(Int32(data=3)))
        assert len(got) >= 5 and all(value(m) == 3 for m in got)
    finally:
        source.close()
        stranger.close()
