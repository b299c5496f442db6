"""The page of a real ``dxboard run --emulate`` in real headless Chromium.

The daemon runs as a subprocess on the virtual TEDUSAR robot (``tests.daemon.runner``,
short device boot times); Chromium (Debian's package, ``tests/web/chromium.py``) opens the
address it prints. The page loads, shows the board's ten channels by name, and follows the
robot live: after the power-up it shows the PC and the devices on; when the lidar is hung
with ``dxboard inject ... hokuyo hang`` the diagnosis panel names it (or its driver) and the
repairs panel shows the power cycle that cures it.
"""

from __future__ import annotations

import asyncio
from collections.abc import Iterator
from pathlib import Path

import pytest

from tests.daemon.runner import RunningDaemon, fast_copy, healthy
from tests.web.chromium import Chromium

NAMES = ["sensor_head", "laser_alignment", "pc", "hokuyo", "kinect", "router",
         "thermal_camera", "jaguar", "spare8", "spare9"]
HEAL_S = 90.0  # on a busy machine a node's topic may flicker a while after a repair
CHANNEL_STATE = "document.querySelector('[data-channel-id=\"{}\"]')?.dataset.state"
# every chip and repair row the page ever showed, sampled every 20 ms (they come and go)
WATCH = """
window.seenChips = new Set(); window.seenRepairs = new Set();
setInterval(() => {
  document.querySelectorAll('#diagnoses .chip').forEach(c => seenChips.add(c.textContent));
  document.querySelectorAll('#repairs .repair').forEach(r =>
    seenRepairs.add(r.querySelector('.what').textContent + ' ' + r.dataset.state));
}, 20); true
"""


@pytest.fixture(scope="module")
def daemon(tmp_path_factory: pytest.TempPathFactory) -> Iterator[RunningDaemon]:
    tmp = tmp_path_factory.mktemp("page")
    d = RunningDaemon(tmp, fast_copy(tmp),  # as docs/security.md shows the flag
                      extra_args=("--web-allow-origin", "http://robot7.local:8080"))
    try:
        yield d
    finally:
        d.close()



async def test_the_daemon_page_shows_the_robot_and_a_fault(daemon: RunningDaemon,
                                                           tmp_path: Path) -> None:
    await asyncio.to_thread(daemon.wait_for, healthy, 90.0, "the robot up and healthy")
    async with Chromium.launch(daemon.urls["web"]) as page:
        assert await page.wait_for("document.querySelectorAll('.channel').length", 30) == 10
        names = await page.evaluate(
            "[...document.querySelectorAll('.channel .name')].map(e => e.textContent)")
        assert names == NAMES
        for ch in (2, 3, 7):  # the PC and the devices the daemon powered up
            assert await page.wait_for(f"{CHANNEL_STATE.format(ch)} === 'on'", 30)
        assert await page.wait_for("document.querySelector('#diagnoses .muted')"
                                   "?.textContent === 'none'", HEAL_S)
        assert await page.evaluate(
            "[...document.querySelectorAll('#repairs .what')].some(e =>"
            " e.textContent === 'power_up(hokuyo)')")
        await page.evaluate(WATCH)

        await asyncio.to_thread(daemon.inject, "hokuyo", "hang")
        assert await page.wait_for(
            "['hokuyo', 'hokuyo_node'].some(c => seenChips.has(c))", HEAL_S)
        assert await page.wait_for("seenRepairs.has('power_cycle(hokuyo) succeeded')", 90)
        await asyncio.to_thread(daemon.wait_for, healthy, 90.0, "healthy again")
        assert await page.wait_for("document.querySelector('#diagnoses .muted')"
                                   "?.textContent === 'none'", HEAL_S)
        assert await page.wait_for(f"{CHANNEL_STATE.format(3)} === 'on'", 30)
        await page.screenshot(tmp_path / "daemon-page.png")


async def test_clients_that_hang_up_leave_no_traceback_and_strangers_are_refused(
        daemon: RunningDaemon) -> None:
    import aiohttp
    from yarl import URL

    from tests.web.test_guard import hang_up

    web = URL(daemon.urls["web"])
    assert web.port is not None
    for i in range(20):  # a browser tab closed mid-load, mid-handshake, mid-journal
        for path, upgrade in (("/ws", True), ("/api/journal?limit=1000", False), ("/", False)):
            await hang_up(web.port, path, upgrade, 0.02 * (i % 3))
    async with aiohttp.ClientSession() as s, s.get(web / "api/status") as resp:
        assert resp.status == 200  # it answers still, and said nothing loud about the above
    assert "Traceback" not in daemon.err_path.read_text()
    async with aiohttp.ClientSession() as s:
        async with s.get(web / "ws", headers={"Origin": "http://evil.example"}) as resp:
            assert resp.status == 403 and "evil.example" in await resp.text()
        async with s.get(web / "api/status", headers={"Host": "rebound.example"}) as resp:
            assert resp.status == 403
        async with s.ws_connect(web / "ws", origin=str(web.origin())) as ws:
            assert (await ws.receive_json(timeout=60))["type"] == "status"
        for allowed in ({"Origin": "http://robot7.local:8080"}, {"Host": "robot7.local:8080"}):
            async with s.get(web / "api/status", headers=allowed) as resp:
                assert resp.status == 200, allowed
    assert "Traceback" not in daemon.err_path.read_text()
