"""Watching a running robot over Zenoh: every key's samples, into a ``Recording``.

``ZenohWatcher(rec, connect, auth)`` is a Zenoh peer that connects to the robot's endpoint (the
daemon's, ``tcp/127.0.0.1:7447`` by default, as ``make run`` starts it) with the daemon's
credentials file (``host.observers.sources.zenoh_auth``) and subscribes to every key (``**``). A
Zenoh peer routes no data for others: the watcher learns of the robot's publishers by gossip
through the endpoint and connects to each on the loopback port it listens on (the robot's
convention, ``emulator.robot.bus``). It listens on nothing itself: when both sides of a pair
dial each other at once, Zenoh may drop both links and never retry (a third of the watches of
the virtual robot heard none of some nodes' topics), so only the watcher dials. Each sample's
arrival is noted on the monotonic clock under its topic (``/`` and the key, less ``prefix``),
with the publisher's own stamp where its JSON payload carries one
(``host.observers.payload.stamp_of``). Zenoh has no node graph: no node is seen (``present()``
is empty) and ``host.learn.infer`` names each topic's publisher for the review. ``count`` and
``close`` are those of ``host.learn.live.RosWatcher``, so the probe works alike.
"""

from __future__ import annotations

import threading
import time
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from host.learn.recording import Recording
from host.observers.payload import decode, stamp_of
from host.observers.sources.zenoh_peer import DEFAULT_ENDPOINT, zenoh_config


class ZenohWatcher:
    def __init__(self, rec: Recording, connect: Sequence[str] = (DEFAULT_ENDPOINT,),
                 auth: Path | None = None, prefix: str = "") -> None:
        import zenoh

        self.rec = rec
        self.lock = threading.Lock()
        self.prefix = prefix.strip("/")
        self.session = zenoh.open(zenoh_config([], list(connect), auth=auth))
        key = f"{self.prefix}/**" if self.prefix else "**"
        self._sub: Any = self.session.declare_subscriber(key, self._on)
        self._closed = False

    def _topic(self, key: str) -> str:
        if self.prefix and key.startswith(self.prefix + "/"):
            key = key[len(self.prefix) + 1:]
        return "/" + key

    def _on(self, sample: Any) -> None:  # on a zenoh thread
        now = time.monotonic()
        stamp = stamp_of(decode(sample.payload.to_bytes()))
        with self.lock:
            self.rec.add(self._topic(str(sample.key_expr)), now, stamp=stamp)

    def count(self, topic: str, since: float) -> int:
        """Messages of ``topic`` sent at ``since`` or later (``Recording.sent_since``)."""
        with self.lock:
            return self.rec.sent_since(topic, since)

    def present(self) -> set[str]:
        """No node graph over Zenoh."""
        return set()

    def close(self) -> None:
        if self._closed:
            return
        self._closed = True
        self._sub.undeclare()
        self.session.close()  # type: ignore[no-untyped-call]  # zenoh's stub lacks -> None
