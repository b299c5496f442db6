"""The publisher helper driver processes use to put their topics on the robot's Zenoh network.

``TopicPublisher(connect=[endpoint])`` opens a zenoh peer session connected to the daemon's
endpoint; ``put(topic, values)`` publishes one JSON object (the ``payload`` convention), so the
daemon's observers see the topic's rate and can pick values by key. Synchronous on purpose: a
driver is often a plain loop. Also a small command for scripts and tests::

    python -m host.observers.publisher --connect tcp/127.0.0.1:7447 --rate 20 /odom \\
        --value 'yaw_rate=0.1+0.5*t'        # t: seconds since start; repeat --value for more

runs until killed, publishing at ``--rate`` Hz (``--count N`` stops after N messages); each
message carries ``seq`` and its ``stamp`` (the publisher's monotonic clock, seconds).
``dxboard run``'s endpoint admits only peers with its credentials: ``auth`` (``--auth FILE``)
is its credentials file (``host.observers.sources.zenoh_auth``; ``$DXBOARD_ZENOH_AUTH`` in the
processes it starts).
"""

from __future__ import annotations

import argparse
import math
import os
import time
from collections.abc import Mapping, Sequence
from pathlib import Path
from types import TracebackType
from typing import Any

import zenoh

from host.observers.payload import encode
from host.observers.sources.zenoh_auth import ENV
from host.observers.sources.zenoh_peer import DEFAULT_ENDPOINT, key_of, zenoh_config


class TopicPublisher:
    def __init__(self, connect: Sequence[str] = (DEFAULT_ENDPOINT,), listen: Sequence[str] = (),
                 prefix: str = "", multicast: bool = False, auth: Path | None = None) -> None:
        self.prefix = prefix
        self.session = zenoh.open(zenoh_config(listen, connect, multicast, auth))
        self._pubs: dict[str, zenoh.Publisher] = {}

    def put(self, topic: str, values: Mapping[str, Any] | bytes = b"") -> None:
        pub = self._pubs.get(topic)
        if pub is None:
            pub = self._pubs[topic] = self.session.declare_publisher(key_of(topic, self.prefix))
        pub.put(values if isinstance(values, bytes) else encode(values))

    def close(self) -> None:
        if not self.session.is_closed():
            for pub in self._pubs.values():
                pub.undeclare()  # type: ignore[no-untyped-call]  # zenoh's stub
            self.session.close()  # type: ignore[no-untyped-call]

    def __enter__(self) -> TopicPublisher:
        return self

    def __exit__(self, exc_type: type[BaseException] | None, exc: BaseException | None,
                 tb: TracebackType | None) -> None:
        self.close()


def _expr(text: str) -> tuple[str, str]:
    key, sep, expr = text.partition("=")
    if not sep or not key:
        raise argparse.ArgumentTypeError(f"{text!r} is not KEY=EXPRESSION, e.g. v=0.5*t")
    return key, expr


def main(argv: Sequence[str] | None = None) -> None:
    ap = argparse.ArgumentParser(description="publish a topic at a rate (JSON objects)")
    ap.add_argument("topic")
    ap.add_argument("--connect", action="append", default=[])
    ap.add_argument("--prefix", default="")
    ap.add_argument("--auth", type=Path, default=None,
                    help="the daemon's zenoh credentials file (default $DXBOARD_ZENOH_AUTH)")
    ap.add_argument("--rate", type=float, default=10.0)
    ap.add_argument("--count", type=int, default=0, help="stop after N messages (0: never)")
    ap.add_argument("--value", action="append", type=_expr, default=[],
                    help="KEY=EXPRESSION in t (seconds since start), math functions allowed")
    args = ap.parse_args(argv)
    env: dict[str, Any] = {k: getattr(math, k) for k in dir(math) if not k.startswith("_")}
    code = [(k, compile(e, k, "eval")) for k, e in args.value]
    auth = args.auth or (Path(os.environ[ENV]) if os.environ.get(ENV) else None)
    with TopicPublisher(args.connect or [DEFAULT_ENDPOINT], prefix=args.prefix,
                        auth=auth) as pub:
        start = time.monotonic()
        n = 0
        while not args.count or n < args.count:
            t = time.monotonic() - start
            values = {k: float(eval(c, {**env, "t": t})) for k, c in code}
            pub.put(args.topic, {"seq": n, "stamp": round(start + t, 6), **values})
            n += 1
            time.sleep(max(0.0, start + n / args.rate - time.monotonic()))


if __name__ == "__main__":
    main()
