"""The daemon gives each frequency observer the processes its topic depends on (real processes).

``dxboard run --emulate`` in-process (``host.launch.robot``): the emulated board and devices run
as a child process, the power-up repair starts the nodes as processes. Once the lidar's driver
runs, the /scan observer's probe names the emulator (it feeds the hokuyo), the driver's process
and the daemon itself (its middleware threads receive the messages), and reads a run-queue wait
from /proc; /odom's names the emulator (the jaguar) but not the lidar's driver.
"""

from __future__ import annotations

import os
from pathlib import Path

import psutil

from host.daemon.core import DaemonOptions
from host.experiment.robot import fast_model
from host.launch.robot import Launch, LaunchedRobot
from host.observers import FrequencyObserver
from host.observers.starvation import WaitProbe
from tests.daemon.runner import TEDUSAR
from tests.ports import zenoh_endpoint
from tests.wait import wait_until_async


def _observer(robot: LaunchedRobot, topic: str) -> FrequencyObserver:
    return next(o for o in robot.daemon.hub.observers
                if isinstance(o, FrequencyObserver) and o.topics == (topic,))


async def test_the_scan_observer_reads_the_lidar_chains_processes(tmp_path: Path) -> None:
    system = fast_model(TEDUSAR, tmp_path)
    opts = DaemonOptions(system_dir=system, board_url="", journal=tmp_path / "j.sqlite",
                         zenoh_listen=[zenoh_endpoint()])
    async with LaunchedRobot(Launch(system, daemon=opts)) as robot:
        assert robot.emulated is not None
        emulator = robot.emulated.proc.pid
        assert robot.daemon.opts.device_pids["hokuyo"] == emulator
        probe = _observer(robot, "/scan").probe
        assert isinstance(probe, WaitProbe)
        watcher = robot.daemon.hub.watcher
        assert watcher is not None
        driver = await wait_until_async(lambda: watcher.pid("hokuyo_node"), 120.0,
                                        "the power-up to start hokuyo_node")
        assert "hokuyo_node" in " ".join(psutil.Process(driver).cmdline())
        assert set(probe.pids()) == {os.getpid(), emulator, driver}
        first = probe.wait()
        assert first is not None and first >= 0.0
        # the emulated robot's other topics are wired too, each to its own chain
        odom = _observer(robot, "/odom").probe
        assert isinstance(odom, WaitProbe) and emulator in odom.pids()
        assert driver not in odom.pids()
