"""Ports a launcher must name before the server that listens on them starts.

Most servers here listen on port 0 and report the port they got; that is always safe. A few
must be told a port first: the daemon's zenoh endpoint, which the nodes it starts dial, in an
experiment's robot session or a benchmark's emulator. ``free_port()`` picks a random port
*below* the kernel's ephemeral range (``ip_local_port_range``), free at the moment of asking:
the kernel never hands such a port to anybody's ``bind(0)`` or ``connect()``. A port chosen by
``bind(0)`` and released is the next ``bind(0)``'s to take: the emulated robot's devices bind
theirs so, and one once took the zenoh endpoint's, which made its driver dial zenoh instead of
the device. Only another explicit chooser can take a port between this check and its bind.
For that rare case, ``CLASH`` is the text every listener here reports and ``clashed(text)``
lets a starter retry on a fresh port; ``zenoh_endpoint()`` is a fresh zenoh endpoint so.
"""

from __future__ import annotations

import random
import socket
from pathlib import Path

LOWEST = 20000  # above the well-known and most registered services
CLASH = ("Address already in use", "EADDRINUSE")  # CPython and Rust; MicroPython


def _ephemeral_low() -> int:
    try:
        return int(Path("/proc/sys/net/ipv4/ip_local_port_range").read_text().split()[0])
    except (OSError, ValueError, IndexError):
        return 32768


def _free(port: int, kind: socket.SocketKind) -> bool:
    with socket.socket(socket.AF_INET, kind) as s:
        try:
            s.bind(("", port))  # any address: taken if bound on any of them
        except OSError:
            return False
        return True


def free_port(kind: socket.SocketKind = socket.SOCK_STREAM) -> int:
    """A random port below the ephemeral range that nothing is bound to right now."""
    high = _ephemeral_low()
    for _ in range(1000):
        port = random.randrange(LOWEST, high)
        if _free(port, kind):
            return port
    raise RuntimeError(f"no free port between {LOWEST} and {high}")


def zenoh_endpoint() -> str:
    """A zenoh endpoint on a port from ``free_port()``."""
    return f"tcp/127.0.0.1:{free_port()}"


def clashed(text: str) -> bool:
    """True when a listener failed because another process took its port first."""
    return any(c in text for c in CLASH)
