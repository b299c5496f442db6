"""The Zenoh topic source: Eclipse Zenoh (``eclipse-zenoh`` 1.x) in peer mode, no router.

Zenoh is a publish/subscribe middleware that needs no broker: peers connect to each other
directly (it is also what ROS 2's rmw_zenoh runs on). The daemon's session *listens* on a
loopback endpoint (default ``tcp/127.0.0.1:7447``); driver processes' publishers *connect* to
it (``host.observers.publisher``), and gossip lets peers that joined through it find each
other. Multicast scouting is off by default, so nothing is sent to the network: the robot's
topics stay on the robot unless ``listen``/``connect`` name other endpoints. Shared memory is
off: zenoh would hand a message of 3 KB or more (a scan) over a publisher's 16 MB pool in
``/dev/shm``, and a receiver keeps every sender's pool mapped for good once the sender has gone
(eclipse-zenoh/zenoh#2787): the daemon would grow by 19 MB with each restart of a driver.
Without it, such peers send to the daemon over the loopback link like any other.
With ``auth`` (a credentials file, ``host.observers.sources.zenoh_auth``) the session presents
those credentials and accepts links only from peers that present them too.

Topic names map to key expressions by dropping the leading slash and adding ``prefix``:
``/odom`` is ``odom`` (or ``robot1/odom`` with prefix ``robot1``). Zenoh calls subscribers on
its own threads; each sample is stamped with the source's clock there and handed to the
asyncio loop through the source's inbox (``TopicSource._post``: one wakeup per batch), so
callbacks run on the loop's thread in order.
"""

from __future__ import annotations

import asyncio
import json
import logging
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import zenoh

from host.observers.payload import TopicMessage
from host.observers.sources import zenoh_auth
from host.observers.sources.base import Callback, Subscription, TopicSource, check_topic

log = logging.getLogger(__name__)

DEFAULT_ENDPOINT = "tcp/127.0.0.1:7447"


def zenoh_config(listen: Sequence[str] = (), connect: Sequence[str] = (),
                 multicast: bool = False, auth: Path | None = None) -> zenoh.Config:
    """A peer-mode configuration: these endpoints only, multicast scouting off by default, no
    shared memory, authenticated by the credentials file ``auth`` if given (see the module's
    docstring)."""
    cfg = zenoh.Config()
    cfg.insert_json5("mode", '"peer"')
    cfg.insert_json5("transport/shared_memory/enabled", "false")
    cfg.insert_json5("scouting/multicast/enabled", json.dumps(multicast))
    cfg.insert_json5("listen/endpoints", json.dumps(list(listen)))
    cfg.insert_json5("connect/endpoints", json.dumps(list(connect)))
    zenoh_auth.apply(cfg, auth)
    return cfg


def key_of(topic: str, prefix: str = "") -> str:
    """The key expression of ``topic`` (``/odom`` -> ``odom``, or ``prefix/odom``)."""
    key = check_topic(topic)[1:]
    return f"{prefix.strip('/')}/{key}" if prefix.strip("/") else key


class _ZenohSubscription(Subscription):
    def __init__(self, sub: Any) -> None:
        self._sub = sub
        self._open = True

    def close(self) -> None:
        if self._open:
            self._open = False
            self._sub.undeclare()


class ZenohSource(TopicSource):
    """A zenoh peer session (open at construction) that observers subscribe through."""

    def __init__(self, listen: Sequence[str] = (DEFAULT_ENDPOINT,),
                 connect: Sequence[str] = (), prefix: str = "", multicast: bool = False,
                 auth: Path | None = None, **kwargs: Any) -> None:
        super().__init__(**kwargs)
        self.prefix = prefix
        self.session = zenoh.open(zenoh_config(listen, connect, multicast, auth))
        self._subs: list[_ZenohSubscription] = []
        log.info("zenoh peer %s listening on %s, connecting to %s",
                 self.session.zid(), list(listen), list(connect))

    def subscribe(self, topic: str, callback: Callback) -> Subscription:
        loop = asyncio.get_running_loop()
        clock = self.clock

        def on_sample(sample: zenoh.Sample) -> None:  # on a zenoh thread
            self._post(loop, callback, TopicMessage(clock(), topic, sample.payload.to_bytes()))

        sub = _ZenohSubscription(
            self.session.declare_subscriber(key_of(topic, self.prefix), on_sample))
        self._subs.append(sub)
        return sub

    def _close(self) -> None:
        for sub in self._subs:
            sub.close()
        self.session.close()  # type: ignore[no-untyped-call]  # zenoh's stub lacks -> None
