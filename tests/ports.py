"""Ports for tests that must name one in advance, safe with a second copy of the suite beside.

Most servers in the tests listen on port 0 and print the port they got; that is always safe.
A few must be told a port first (a zenoh endpoint that other processes connect to, an emulator
restarted on the address its client keeps dialling, a UDP multicast bus). ``free_port()`` is
the launcher's (``host.launch.ports``): a random port *below* the kernel's ephemeral range,
free at the moment of asking, which only another explicit chooser can take before our bind.
For that rare case (and for the micropython runtime of the emulator, which picks its ports
itself), ``CLASH`` is the text every listener here reports and ``clashed(text)`` lets a
starter retry on a fresh port (both the launcher's too, as is ``zenoh_endpoint()``).

``reserved_udp_port()`` holds a UDP port for the duration of a test (a socket bound with
SO_REUSEADDR, which the python-can multicast bus also sets): Linux delivers multicast to every
socket bound to the port whatever group it joined, so two suites must never share one.
"""

from __future__ import annotations

import contextlib
import socket
from collections.abc import Iterator

from host.launch.ports import CLASH, clashed, free_port, zenoh_endpoint

__all__ = ["CLASH", "clashed", "free_port", "reserved_udp_port", "zenoh_endpoint"]


@contextlib.contextmanager
def reserved_udp_port() -> Iterator[int]:
    """A UDP port nobody else on this machine binds while the block runs (see the module)."""
    port = free_port(socket.SOCK_DGRAM)  # checked without SO_REUSEADDR: nobody has it
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as held:
        held.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
        held.bind(("127.0.0.1", port))  # others' checks now fail; the bus's reusing binds not
        yield port
