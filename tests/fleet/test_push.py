"""Push (docs/fleet.md): a robot behind NAT runs Prometheus in agent mode, which scrapes its
daemon and remote-writes to the fleet's Prometheus (``--web.enable-remote-write-receiver``);
the fleet's Prometheus then answers for that robot as if it had scraped it. Real parts: one
lightweight emulated robot, the real agent and receiver, on free loopback ports in tmp_path."""

from __future__ import annotations

from pathlib import Path

from benchmarks._rigs.robots import lite_model
from host.launch.prometheus import prometheus, prometheus_agent, query
from tests.daemon.runner import RunningDaemon
from tests.wait import wait_until


def test_a_robot_pushes_its_metrics_by_remote_write(tmp_path: Path) -> None:
    robot = RunningDaemon(tmp_path, lite_model(tmp_path),
                          ("--middleware", "zenoh", "-q", "--robot", "rover-nat", "--site",
                           "yard"))
    try:
        with prometheus(tmp_path / "fleet", [], extra=["--web.enable-remote-write-receiver"]) \
                as fleet:
            target = robot.urls["web"].removeprefix("http://").rstrip("/")
            with prometheus_agent(tmp_path / "agent", [target], f"{fleet}/api/v1/write"):
                got = wait_until(
                    lambda: query(fleet, 'dxboard_board_link_up{robot="rover-nat"} == 1'),
                    120, "rover-nat's metrics pushed to the fleet's Prometheus", interval=0.5)
                assert got[0]["metric"]["site"] == "yard"
                health = query(fleet, 'dxboard_component_health{robot="rover-nat"}')
                assert {s["metric"]["component"] for s in health} >= {"hokuyo", "jaguar"}
    finally:
        robot.close()
