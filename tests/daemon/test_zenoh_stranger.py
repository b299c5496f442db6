"""A stranger's zenoh session cannot reach the daemon's endpoint, so its /odom repairs nothing.

The finding (issue 25 item 5): a process publishing ``/odom`` at 300 Hz on ``dxboard run``'s
zenoh endpoint made the daemon power-cycle the healthy base twice. Now the endpoint requires
zenoh's user/password authentication, and the robot's nodes the daemon starts get the
credentials from it (``$DXBOARD_ZENOH_AUTH``, a file only the daemon's user can read): the
robot powers up healthy through authenticated links, while a plain zenoh session, as anyone
on the robot could open it, gets no link and causes no repair over a generous window.
"""

from __future__ import annotations

import json
import time
from pathlib import Path

import zenoh

from tests.daemon.runner import actions_started, healthy_robot, last_id

SPOOF_S = 15.0  # the window the stranger publishes in (the finding: 2 repairs in it)


def test_a_stranger_without_credentials_gets_no_link_and_causes_no_repair(
        tmp_path: Path) -> None:
    # the robot powers up: its nodes' links to the daemon are authenticated
    with healthy_robot(tmp_path, heal_s=180.0) as d:
        mark = last_id(d)
        cfg = zenoh.Config()
        cfg.insert_json5("mode", '"peer"')
        cfg.insert_json5("scouting/multicast/enabled", "false")
        cfg.insert_json5("connect/endpoints", json.dumps([d.zenoh]))
        session = zenoh.open(cfg)
        try:
            odom = session.declare_publisher("odom")
            end = time.monotonic() + SPOOF_S
            sent = 0
            while time.monotonic() < end:  # 300 Hz, a spinning base
                odom.put(json.dumps({"yaw": 3.0 * sent / 300, "yaw_rate": 3.0}).encode())
                sent += 1
                time.sleep(1 / 300)
            assert list(session.info.peers_zid()) == []  # never linked to anyone
        finally:
            session.close()  # type: ignore[no-untyped-call]
        d.settled(2.0, runs=3)
        assert actions_started(d, mark) == []
        auth = tmp_path / "journal-zenoh.auth"  # the nodes' credentials: the daemon's only
        assert auth.stat().st_mode & 0o777 == 0o600
