"""The experiments' robot session names its zenoh port before the emulated robot starts: a port
the kernel never hands to a ``bind(0)``, so no device of the emulated robot can be given it.

M1 once never came up: the session's port came from ``bind(0)``, was released, and the emulated
jaguar's own ``bind(0)`` got it next; the jaguar's driver then dialled zenoh instead of the
device and /odom never flowed (tests/robot/test_devices.py holds the device's side)."""

from __future__ import annotations

import socket
from pathlib import Path

from host.experiment.session import RobotSession
from host.launch.ports import free_port

ROOT = Path(__file__).resolve().parents[2]


def ephemeral() -> range:
    low, high = (int(x) for x in
                 Path("/proc/sys/net/ipv4/ip_local_port_range").read_text().split())
    return range(low, high + 1)


def test_the_sessions_zenoh_port_is_never_one_a_bind_to_port_0_is_given(tmp_path: Path) -> None:
    given = set()
    for _ in range(20):
        with socket.socket() as s:
            s.bind(("127.0.0.1", 0))
            given.add(s.getsockname()[1])
    assert given <= set(ephemeral())  # what a device's bind(0) may be given
    for _ in range(50):
        session = RobotSession(ROOT / "models" / "tedusar", tmp_path / "journal.sqlite")
        opts = session.robot.launch.daemon
        assert opts is not None
        (endpoint,) = opts.zenoh_listen
        port = int(endpoint.rpartition(":")[2])
        assert port not in ephemeral() and port >= 1024, endpoint


def test_a_chosen_port_is_free_for_a_listener() -> None:
    port = free_port()
    with socket.socket() as s:
        s.bind(("127.0.0.1", port))
        s.listen()
