"""``--probe`` on the emulated TEDUSAR board: each unprotected channel off in turn, at most 2 s,
every one on again (after an error or Ctrl-C too), the protected one never touched.

The in-process tests drive ``host.learn.board.probe`` with a real ``BoardClient`` on the
emulator (``dxboard emulate models/tedusar --robot``), wrapped to note every switch it asks
for (the board still does each one). The end-to-end test runs ``dxboard model learn --board
--probe`` while the virtual Hokuyo's ROS 2 driver publishes ``/scan``: the learned model has
the Hokuyo as switchable hardware on its channel with a current band, and its driver as the
node that drives it.
"""

from __future__ import annotations

import asyncio
import contextlib
import time
from pathlib import Path
from typing import Any

import pytest

from host.board.client import BoardClient
from host.diagnosis.model import ComponentKind, load_system
from host.learn.board import OFF_S, probe, watch_board
from host.learn.recording import Recording
from host.learn.session import check_written
from tests.robot.conftest import KEY_HEX, Robot
from tests.ros.conftest import Peer, RosNodes
from tests.ros.test_bags import dxboard

PROTECTED = 2  # the TEDUSAR board's pc channel


class Noting:
    """A real client that notes every switch asked for, with the time."""

    def __init__(self, client: BoardClient, cancel_after: int | None = None) -> None:
        self.client = client
        self.switches: list[tuple[int, bool, float]] = []
        self.cancel_after = cancel_after

    def __getattr__(self, name: str) -> Any:
        return getattr(self.client, name)

    async def switch(self, ch: int, on: bool, force: bool = False) -> Any:
        assert not force
        self.switches.append((ch, on, time.monotonic()))
        result = await self.client.switch(ch, on, force)
        if self.cancel_after is not None and len(self.switches) >= self.cancel_after:
            raise asyncio.CancelledError  # Ctrl-C while a channel is off
        return result


class NoTopics:
    def count(self, topic: str, since: float) -> int:
        return 0

    def present(self) -> set[str]:
        return set()


async def probed(url: str, cancel_after: int | None = None) -> tuple[Noting, set[int], Any]:
    async with BoardClient(url, bytes.fromhex(KEY_HEX)) as client:
        for ch in range(10):
            if ch != PROTECTED:
                await client.switch(ch, True)
        on_before = {c.channel for c in (await client.state()).channels if c.commanded}
        noting = Noting(client, cancel_after)
        rec = Recording(time.monotonic(), 0.0)
        await watch_board(client, rec, time.monotonic() + 1.0)
        with contextlib.suppress(asyncio.CancelledError):
            await probe(noting, rec, NoTopics(), lambda line: None)
        return noting, on_before, await client.state()


def check_restored(noting: Noting, on_before: set[int], after: Any) -> None:
    assert PROTECTED not in {ch for ch, _, _ in noting.switches}
    assert {c.channel for c in after.channels if c.commanded} == on_before
    offs = {ch: t for ch, on, t in noting.switches if not on}
    for ch, t_off in offs.items():
        t_on = min(t for c, on, t in noting.switches if c == ch and on and t >= t_off)
        assert t_on - t_off < 2.0 + 1.0  # OFF_S plus the round trip of a busy machine
    assert OFF_S < 2.0


def test_the_probe_restores_every_channel_and_skips_the_protected_one(robot: Robot) -> None:
    noting, on_before, after = asyncio.run(probed(robot.urls["board"]))
    assert PROTECTED in on_before  # the pc is on, and stays untouched
    assert {ch for ch, on, _ in noting.switches if not on} == on_before - {PROTECTED}
    check_restored(noting, on_before, after)


def test_ctrl_c_while_a_channel_is_off_switches_it_on_again(robot: Robot) -> None:
    noting, on_before, after = asyncio.run(probed(robot.urls["board"], cancel_after=1))
    assert [(ch, on) for ch, on, _ in noting.switches] == [(noting.switches[0][0], False),
                                                            (noting.switches[0][0], True)]
    check_restored(noting, on_before, after)


@pytest.mark.timeout(600)
def test_learn_with_the_probe_finds_the_hokuyo_and_its_driver(
        tmp_path: Path, robot: Robot, ros_nodes: RosNodes, peer: Peer,
        env: dict[str, str]) -> None:
    from sensor_msgs.msg import LaserScan

    robot.board("on", "hokuyo")
    ros_nodes.start("hokuyo_node")
    peer.listen("/scan", LaserScan)
    peer.collect("/scan", 20, 120.0)
    out = tmp_path / "learned"
    board = robot.urls["board"].removeprefix("tcp://")
    p = dxboard("model", "learn", str(out), "--duration", "6", "--board", board, "--probe",
                env={**env, "DXBOARD_KEY": KEY_HEX})
    assert p.returncode == 0, p.stderr
    assert "probing" in p.stderr and "every one switched on again" in p.stderr
    assert check_written(out) == []
    model = load_system(out)
    hokuyo = model.components["hokuyo"]
    assert (hokuyo.kind, hokuyo.channel) == (ComponentKind.SH, 3)
    assert hokuyo.current is not None and hokuyo.current[0] > 0
    driver = model.components["hokuyo_node"]
    assert (driver.kind, driver.hardware) == (ComponentKind.SN, ("hokuyo",))
    assert model.protected == frozenset({PROTECTED})
    assert all(c.channel != PROTECTED for c in model.components.values())
    assert robot.channel("hokuyo")["commanded"]


PERIOD = 0.1


class NeverBack:
    """Topic /a is published every ``PERIOD`` until the first channel's probe switches it off
    and never again (a driver that does not reconnect); /b goes on throughout."""

    def __init__(self, noting: Noting) -> None:
        self.noting = noting

    def count(self, topic: str, since: float) -> int:
        """Messages sent at ``since`` or later, one every ``PERIOD`` s."""
        offs = [t for _, on, t in self.noting.switches if not on]
        until = time.monotonic() if topic == "/b" or not offs else offs[0]
        return max(0, int((until - since) / PERIOD))

    def present(self) -> set[str]:
        return set()


def test_a_topic_that_never_comes_back_is_no_later_probes_evidence(robot: Robot) -> None:
    async def run() -> Recording:
        async with BoardClient(robot.urls["board"], bytes.fromhex(KEY_HEX)) as client:
            for ch in (0, 1, 3):
                await client.switch(ch, True)
            rec = Recording(time.monotonic(), 0.0)
            rec.add("/a", time.monotonic())
            rec.add("/b", time.monotonic())
            await watch_board(client, rec, time.monotonic() + 0.5)
            noting = Noting(client)
            await probe(noting, rec, NeverBack(noting), lambda line: None)
            return rec

    rec = asyncio.run(run())
    first, *later = rec.probes
    assert (first.stopped, first.kept, first.lost) == (("/a",), ("/b",), ("/a",))
    assert later and all(p.stopped == () and p.kept == ("/b",) for p in later)
