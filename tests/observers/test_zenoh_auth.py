"""The daemon's zenoh endpoint admits only peers with its credentials (issue 25 item 5).

Real zenoh sessions on loopback: the source listens with a credentials file
(``host.observers.sources.zenoh_auth``); a stranger's plain session (no credentials, or a
wrong password) publishing ``/odom`` gets no link and delivers nothing, while the robot's
emulated node bus (``emulator.robot.bus``, which shares no code with the host) given the same
file delivers. The file is made private (0600) once and reused; a file others can read is
refused with the place and the fix.
"""

from __future__ import annotations

import asyncio
import json
import os
import subprocess
from collections.abc import AsyncIterator
from pathlib import Path
from typing import Any

import pytest
import zenoh

from emulator.robot.bus import Bus
from host.errors import UserError
from host.observers.payload import TopicMessage
from host.observers.sources.zenoh_auth import beside, credentials_file, read
from host.observers.sources.zenoh_peer import ZenohSource
from tests.observers.conftest import PYTHON
from tests.wait import wait_until_async


def stranger(endpoint: str, user: str | None = None, password: str | None = None) -> Any:
    """A plain zenoh peer session as anyone on the robot could open it."""
    cfg = zenoh.Config()
    cfg.insert_json5("mode", '"peer"')
    cfg.insert_json5("scouting/multicast/enabled", "false")
    cfg.insert_json5("connect/endpoints", json.dumps([endpoint]))
    if user is not None:
        cfg.insert_json5("transport/auth/usrpwd",
                         json.dumps({"user": user, "password": password}))
    return zenoh.open(cfg)


def test_a_relative_journal_gives_an_absolute_credentials_path(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    # the path goes to nodes in other working directories (DXBOARD_ZENOH_AUTH): `dxboard
    # experiment ... --journal shutdown.sqlite` gave them 'shutdown-zenoh.auth' and none started
    monkeypatch.chdir(tmp_path)
    path = beside(Path("shutdown.sqlite"))
    assert path.is_absolute() and path == tmp_path / "shutdown-zenoh.auth"
    assert path.exists()


def test_the_credentials_file_is_private_made_once_and_reused(tmp_path: Path) -> None:
    path = credentials_file(tmp_path / "zenoh.auth")
    assert path.stat().st_mode & 0o777 == 0o600
    user, password = read(path)
    assert user == "dxboard" and len(password) >= 24
    assert read(credentials_file(path)) == (user, password)  # a restart keeps it
    os.chmod(path, 0o644)
    with pytest.raises(UserError, match="not a private file") as err:
        credentials_file(path)
    assert "chmod 600" in str(err.value)


class Daemonside:
    """The daemon's side: a source listening with a credentials file, recording ``/odom``."""

    def __init__(self, tmp: Path, endpoint: str) -> None:
        self.auth = credentials_file(tmp / "zenoh.auth")
        self.got: list[TopicMessage] = []
        self.source = ZenohSource(listen=[endpoint], auth=self.auth)
        self.source.subscribe("/odom", self.got.append)


@pytest.fixture
async def daemonside(tmp_path: Path, endpoint: str) -> AsyncIterator[Daemonside]:
    d = Daemonside(tmp_path, endpoint)
    yield d
    d.source.close()


async def test_a_stranger_without_the_credentials_cannot_publish_to_the_endpoint(
        daemonside: Daemonside, endpoint: str) -> None:
    auth, got = daemonside.auth, daemonside.got
    user, _ = read(auth)
    strangers = [stranger(endpoint), stranger(endpoint, user, "guessed")]
    node = Bus(endpoint, auth=str(auth))
    try:
        pubs = [s.declare_publisher("odom") for s in strangers]

        def publish() -> None:
            for p in pubs:
                p.put(b'{"who":"stranger"}')
            node.publish("/odom", {"who": "node"})

        await wait_until_async(lambda: len(got) >= 20, 60.0, "the node's messages",
                               each=publish, show=lambda: len(got))
        for _ in range(20):  # the strangers had every chance
            publish()
            await asyncio.sleep(0.01)
        assert {(m.values or {}).get("who") for m in got} == {"node"}
        assert [list(s.info.peers_zid()) for s in strangers] == [[], []]  # no link at all
    finally:
        node.close()
        for s in strangers:
            s.close()


async def test_the_publisher_command_with_the_credentials_file_reaches_the_endpoint(
        daemonside: Daemonside, endpoint: str) -> None:
    proc = subprocess.Popen([PYTHON, "-m", "host.observers.publisher", "--connect", endpoint,
                             "--auth", str(daemonside.auth), "--rate", "50", "/odom"])
    try:
        await wait_until_async(lambda: len(daemonside.got) >= 5, 60.0,
                               "the publisher's messages")
    finally:
        proc.kill()
        proc.wait()
