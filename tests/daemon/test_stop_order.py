"""A stop judges nothing it causes: the observers close before the nodes are stopped, so the
topics those nodes published do not go "silent" on the terminal while the daemon itself stops
them (``dxboard run`` used to print ``frequency:/odom: silent, no message for 0.240 s`` after
``stopping``). In-process: the daemon is built, not started, and its stages are recorded."""

from __future__ import annotations

from pathlib import Path

import pytest

from host.daemon.core import Daemon, DaemonOptions
from tests.daemon.runner import TEDUSAR


async def test_the_observers_close_before_the_nodes_are_stopped(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    daemon = Daemon(DaemonOptions(system_dir=TEDUSAR, board_url="sim://",
                                  journal=tmp_path / "journal.sqlite"))
    order: list[str] = []
    hub_close, repairs_close = daemon.hub.close, daemon.repairs.close

    async def hub() -> None:
        order.append("observers")
        await hub_close()

    async def repairs() -> None:
        order.append("nodes")
        await repairs_close()

    monkeypatch.setattr(daemon.hub, "close", hub)
    monkeypatch.setattr(daemon.repairs, "close", repairs)
    await daemon.close()
    assert order == ["observers", "nodes"]
