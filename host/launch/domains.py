"""A ROS 2 DDS domain of one's own for the robots a launcher starts side by side (no rclpy here:
importable by any test or benchmark that starts ROS 2 processes, e.g. the daemon's end-to-end
tests parametrized over the middleware).

``claim_domain()`` picks a ``ROS_DOMAIN_ID`` from the process's pid and holds an exclusive
lock file per domain (``/tmp/dxboard-ros-domain-N.lock``) until the block ends, so two suites
beside each other, or two tests of one, or a benchmark beside them, never share a domain.
``domain_env(d)`` is what a process needs to use it, with discovery kept on this machine.
"""

from __future__ import annotations

import contextlib
import fcntl
import os
from collections.abc import Iterator
from pathlib import Path

DOMAINS = 100  # 1..100: Fast DDS's port formula fits them all on one host
_counter = [0]


@contextlib.contextmanager
def claim_domain() -> Iterator[int]:
    """A free domain id, held (by a lock file) until the block ends."""
    _counter[0] += 1
    start = (os.getpid() * 7 + _counter[0]) % DOMAINS
    for i in range(DOMAINS):
        d = 1 + (start + i) % DOMAINS
        f = Path(f"/tmp/dxboard-ros-domain-{d}.lock").open("w")  # noqa: SIM115 - held
        try:
            fcntl.flock(f, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            f.close()
            continue
        try:
            yield d
        finally:
            f.close()
        return
    raise RuntimeError("every ROS 2 domain 1..100 is taken by other robots")


def domain_env(domain: int) -> dict[str, str]:
    """The variables that put a ROS 2 process on ``domain``, discovering on this host only."""
    return {"ROS_DOMAIN_ID": str(domain), "ROS_AUTOMATIC_DISCOVERY_RANGE": "LOCALHOST"}
