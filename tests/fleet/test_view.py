"""``dxboard fleet`` without a working Prometheus, and its bad input (the page against the real
Prometheus is in test_fleet.py)."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import aiohttp

from host.fleet.view import FleetView
from host.launch.ports import free_port
from host.launch.prometheus import prometheus, query
from tests.wait import wait_until_async

ROOT = Path(__file__).resolve().parents[2]


async def test_a_prometheus_that_does_not_answer_is_a_502_naming_it() -> None:
    dead = f"http://127.0.0.1:{free_port()}"  # nothing listens there
    view = FleetView(dead)
    await view.start("127.0.0.1", 0)
    try:
        async with aiohttp.ClientSession() as s:
            async with s.get(f"http://127.0.0.1:{view.port}/api/fleet") as resp:
                assert resp.status == 502
                assert dead in (await resp.json())["error"]
            async with s.get(f"http://127.0.0.1:{view.port}/") as resp:
                assert resp.status == 502
                text = await resp.text()
                assert "Prometheus did not answer" in text and dead in text
    finally:
        await view.close()


def test_a_bad_prometheus_url_is_one_line_and_exit_2() -> None:
    out = subprocess.run([sys.executable, "-m", "host.cli", "fleet", "--prometheus", "nonsense"],
                         capture_output=True, text=True, timeout=60, cwd=ROOT)
    assert out.returncode == 2
    assert out.stderr.strip().count("\n") == 0 and "--prometheus" in out.stderr
    assert "Traceback" not in out.stderr


async def test_a_robot_prometheus_cannot_scrape_is_unreachable(tmp_path: Path) -> None:
    dead = f"127.0.0.1:{free_port()}"  # a robot whose daemon is not there
    with prometheus(tmp_path, [dead]) as url:
        await wait_until_async(lambda: query(url, "up == 0"), 120, "the failed scrape",
                               interval=0.5)
        view = FleetView(url)
        rows = await view.rows()
    assert [(r.robot, r.headline) for r in rows] == [(dead, "unreachable")]
