"""The robot's topics on Eclipse Zenoh, for the node processes: a peer session, JSON payloads.

The same conventions as the host's observers (``host.observers.sources.zenoh_peer``; the
emulator does not import the host, so these few lines are its own): peer mode, multicast
scouting off, *connect* to the daemon's endpoint (``$DXBOARD_ZENOH``, default
``tcp/127.0.0.1:7447``) and listen on a free loopback port so that peers introduced by gossip
can reach each other directly; topic ``/scan`` is key ``scan``; a payload is one JSON object
(compact, UTF-8). Zenoh retries a connection the peer refuses, so a node may start before the
daemon. With ``$DXBOARD_ZENOH_AUTH`` (the daemon's credentials file, one ``user:password``
line, readable only by the daemon's user) the session presents those credentials and its own
listener accepts only peers that present them (``host.observers.sources.zenoh_auth``: a
stranger can join neither the daemon nor a node). Subscribers' callbacks run on zenoh's
threads; ``subscribe`` hands each message to the asyncio loop, in order, through one
``emulator.inbox.Inbox`` per bus: one wakeup of the loop per batch, never one per message (a
flood must not fill the loop's self-pipe, issue 25), oldest dropped and counted past its bound.
"""

from __future__ import annotations

import asyncio
import json
from collections.abc import Callable
from typing import Any, Protocol

import zenoh

from emulator.inbox import Inbox

DEFAULT_ENDPOINT = "tcp/127.0.0.1:7447"
LISTEN = "tcp/127.0.0.1:0"

Handler = Callable[[str, dict[str, Any]], None]
Delivery = tuple[Handler, str, dict[str, Any]]  # a message on its way to its handler


def _deliver(item: Delivery) -> None:
    handler, topic, values = item
    handler(topic, values)


def inbox_for(loop: asyncio.AbstractEventLoop) -> Inbox[Delivery]:
    """The hand-over point of a bus's messages to ``loop`` (either middleware)."""
    return Inbox(loop, _deliver, name="topic messages")


class TopicBus(Protocol):
    """What a node publishes and subscribes through: ``Bus`` (zenoh) or
    ``emulator.robot.ros_bus.RosBus`` (ROS 2)."""

    def publish(self, topic: str, values: dict[str, Any]) -> None: ...

    def subscribe(self, topic: str, handler: Handler) -> None: ...

    def close(self) -> None: ...


def key_of(topic: str) -> str:
    if not topic.startswith("/") or len(topic) < 2:
        raise ValueError(f"a topic starts with / (e.g. /scan), not {topic!r}")
    return topic[1:]


def encode(values: dict[str, Any]) -> bytes:
    return json.dumps(values, separators=(",", ":"), allow_nan=False).encode()


def decode(payload: bytes) -> dict[str, Any]:
    """The JSON object in ``payload`` ({} when it is not one: it still counts as a message)."""
    try:
        obj = json.loads(payload)
    except (UnicodeDecodeError, ValueError):
        return {}
    return obj if isinstance(obj, dict) else {}


def auth_config(path: str) -> str:
    """The ``transport/auth/usrpwd`` value (JSON) for the credentials file ``path``."""
    with open(path) as f:
        user, _, password = f.read().strip().partition(":")
    return json.dumps({"user": user, "password": password, "dictionary_file": path})


class Bus:
    def __init__(self, connect: str = DEFAULT_ENDPOINT, listen: str = LISTEN,
                 auth: str | None = None) -> None:
        """``auth``: the daemon's credentials file (``$DXBOARD_ZENOH_AUTH``), if it has one."""
        cfg = zenoh.Config()
        cfg.insert_json5("mode", '"peer"')
        # no shared memory: a receiver keeps a gone sender's 16 MB pool mapped for good
        # (eclipse-zenoh/zenoh#2787), in hector_mapping at each restart of the lidar's driver
        cfg.insert_json5("transport/shared_memory/enabled", "false")
        cfg.insert_json5("scouting/multicast/enabled", "false")
        cfg.insert_json5("listen/endpoints", json.dumps([listen]))
        cfg.insert_json5("connect/endpoints", json.dumps([connect]))
        if auth:
            cfg.insert_json5("transport/auth/usrpwd", auth_config(auth))
        self.session = zenoh.open(cfg)
        self._pubs: dict[str, zenoh.Publisher] = {}
        self._subs: list[Any] = []
        self._inbox: Inbox[Delivery] | None = None

    def publish(self, topic: str, values: dict[str, Any]) -> None:
        pub = self._pubs.get(topic)
        if pub is None:
            pub = self._pubs[topic] = self.session.declare_publisher(key_of(topic))
        pub.put(encode(values))

    def subscribe(self, topic: str, handler: Handler) -> None:
        """Call ``handler(topic, values)`` on the running loop for every message."""
        if self._inbox is None:
            self._inbox = inbox_for(asyncio.get_running_loop())
        inbox = self._inbox

        def on_sample(sample: zenoh.Sample) -> None:  # on a zenoh thread
            inbox.put((handler, topic, decode(sample.payload.to_bytes())))

        self._subs.append(self.session.declare_subscriber(key_of(topic), on_sample))

    def close(self) -> None:
        if self.session.is_closed():
            return
        for sub in self._subs:
            sub.undeclare()
        for pub in self._pubs.values():
            pub.undeclare()  # type: ignore[no-untyped-call]  # zenoh's stub lacks -> None
        self.session.close()  # type: ignore[no-untyped-call]
