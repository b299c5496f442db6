"""The page in real headless Chromium: it loads, shows the board, and follows changes live.

Chromium (Debian's package) is driven over the DevTools protocol (``tests/web/chromium.py``);
the server is real and fed by ``MemoryStatusSource``. The tests change the status, the journal
and the connection and wait for the page's DOM to show it.
"""

from __future__ import annotations

import time
from pathlib import Path

from host.journal import Journal, Note
from host.web import DiagnosisStatus, MemoryStatusSource, OutOfRepair, WebServer
from tests.ports import free_port
from tests.web.chromium import Chromium
from tests.web.demo import kept_fresh

CHANNEL_STATE = "document.querySelector('[data-channel-id=\"{}\"]')?.dataset.state"
PILL = "document.getElementById('conn-state').dataset.state"


async def test_page_shows_the_board_and_follows_changes(
        server: WebServer, source: MemoryStatusSource, journal: Journal) -> None:
    async with kept_fresh(source), Chromium.launch(f"http://127.0.0.1:{server.port}/") as page:
        assert await page.wait_for("document.querySelectorAll('.channel').length") == 10
        names = await page.evaluate(
            "[...document.querySelectorAll('.channel .name')].map(e => e.textContent)")
        assert names[:4] == ["sensor_head", "laser_alignment", "pc", "hokuyo"]
        assert await page.evaluate(CHANNEL_STATE.format(6)) == "tripped"
        assert await page.evaluate(
            "document.querySelectorAll('[data-channel-id=\"3\"] svg.spark polyline').length") == 1
        assert await page.wait_for(f"{PILL} === 'live'")
        chips = await page.evaluate(
            "[...document.querySelectorAll('#diagnoses .diagnosis')].map(d =>"
            " [...d.querySelectorAll('.chip')].map(c => c.textContent))")
        assert chips == [["jaguar_node"], ["jaguar_teleop_node", "jaguar_node"]]
        assert await page.evaluate("document.querySelectorAll('#repairs .repair').length") == 3
        assert await page.evaluate(
            "document.querySelector('.obs[data-value=\"false\"]').dataset.atom") in {
            "ok(jaguar_node)", "ok(jaguar_teleop_node)"}
        assert await page.wait_for("document.querySelectorAll('#journal .row').length") == 13

        # the thermal camera is reset: the channel, the diagnosis and the journal follow
        source.update_channel(6, state="on", on=True, current_ma=2450.0)
        source.update(diagnoses=(DiagnosisStatus((), 1.0),), updated=time.time())
        journal.record(Note("thermal camera back"), wall=time.time(), mono=9000.0)
        assert await page.wait_for(f"{CHANNEL_STATE.format(6)} === 'on'")
        assert await page.evaluate(
            "document.querySelector('[data-channel-id=\"6\"] .current').textContent") == "2.45A"
        assert await page.wait_for(
            "document.querySelector('#diagnoses .healthy')?.textContent")
        assert await page.wait_for(
            "document.querySelector('#journal .row:first-child')?.textContent"
            ".includes('thermal camera back')")


async def test_page_shows_stale_data_and_a_lost_link(
        source: MemoryStatusSource, journal: Journal) -> None:
    web = WebServer(source, journal.reader, push_interval_s=0.05, heartbeat_s=0.5,
                    stale_after_s=5.0)
    # restarted on the same port below: one the kernel never hands to others meanwhile
    port = await web.start("127.0.0.1", free_port())
    async with Chromium.launch(f"http://127.0.0.1:{port}/") as page:
        try:
            async with kept_fresh(source):
                assert await page.wait_for(f"{PILL} === 'live'")
                assert not await page.evaluate("document.body.classList.contains('stale')")
                source.update(board_link_up=False)
                assert await page.wait_for(f"{PILL} === 'board-down'")
                source.update(board_link_up=True, board_key="refused: bad tag")
                assert await page.wait_for(f"{PILL} === 'key-refused'")
                banner = "document.getElementById('banner')"
                assert "--key-file" in await page.evaluate(f"{banner}.textContent")
                assert await page.evaluate(f"getComputedStyle({banner}).display") == "block"
                assert not await page.evaluate("document.body.classList.contains('stale')")
                source.update(board_key="accepted")
                assert await page.wait_for(f"{PILL} === 'live'")
            source.update(board_link_up=True, updated=time.time() - 30)  # the daemon froze
            assert await page.wait_for(f"{PILL} === 'stale'")
            assert await page.evaluate("document.body.classList.contains('stale')")
            assert "s old" in await page.evaluate("document.getElementById('banner').textContent")
            async with kept_fresh(source):  # it is back
                assert await page.wait_for(f"{PILL} === 'live'")
        finally:
            await web.close()
        assert await page.wait_for(f"{PILL} === 'lost'")
        assert "reconnecting" in await page.evaluate(
            "document.getElementById('banner').textContent")
        # the daemon comes back on the same port: the page reconnects by itself
        web = WebServer(source, journal.reader, push_interval_s=0.05, heartbeat_s=0.5)
        await web.start("127.0.0.1", port)
        try:
            async with kept_fresh(source):
                assert await page.wait_for(f"{PILL} === 'live'", timeout=60)
        finally:
            await web.close()


OBS = "document.querySelector('.obs[data-atom=\"{}\"]')"


async def test_page_colours_by_health_lists_repairs_newest_first_and_shows_what_is_set_aside(
        server: WebServer, source: MemoryStatusSource) -> None:
    now = time.time()
    source.update(
        observations={"tripped(hokuyo)": False, "on(hokuyo)": True, "on(jaguar)": False,
                      "tripped(jaguar)": True, "ok(/map)": None, "inc(odom_yaw_rate)": True},
        healthy={"tripped(hokuyo)": False, "on(hokuyo)": True, "on(jaguar)": True,
                 "tripped(jaguar)": False, "ok(/map)": True},
        out_of_repair=(
            OutOfRepair("hokuyo", "quarantined", "3 attempts in 10 min failed", "daemon",
                        now - 120, "dxboard quarantine clear hokuyo", "shutdown(hokuyo)"),
            OutOfRepair("jaguar", "held", "switched off on the board by a command this daemon "
                        "did not send", "board", now - 30, "switch it on again (dxboard board "
                        "tcp://127.0.0.1:7000 on jaguar), or dxboard hold release jaguar")),
        updated=now)
    async with Chromium.launch(f"http://127.0.0.1:{server.port}/") as page:
        assert await page.wait_for(f"{OBS.format('inc(odom_yaw_rate)')}?.dataset.health")
        health = await page.evaluate(
            "Object.fromEntries([...document.querySelectorAll('.obs')].map(e =>"
            " [e.dataset.atom, e.dataset.health]))")
        assert health == {"tripped(hokuyo)": "healthy", "on(hokuyo)": "healthy",
                          "on(jaguar)": "unhealthy", "tripped(jaguar)": "unhealthy",
                          "ok(/map)": "unknown", "inc(odom_yaw_rate)": "free"}
        # a healthy false looks like a healthy true, not like an unhealthy false
        bg = "getComputedStyle({}).backgroundColor"
        healthy_false = await page.evaluate(bg.format(OBS.format("tripped(hokuyo)")))
        assert healthy_false == await page.evaluate(bg.format(OBS.format("on(hokuyo)")))
        assert healthy_false != await page.evaluate(bg.format(OBS.format("on(jaguar)")))
        assert await page.evaluate(bg.format(OBS.format("on(jaguar)"))) == await page.evaluate(
            bg.format(OBS.format("tripped(jaguar)")))
        # each says its value in words; the unhealthy ones come first
        assert await page.evaluate(f"{OBS.format('tripped(hokuyo)')}.textContent") == (
            "tripped(hokuyo) = false")
        first = await page.evaluate(
            "[...document.querySelectorAll('.obs')].slice(0, 2).map(e => e.dataset.atom)")
        assert sorted(first) == ["on(jaguar)", "tripped(jaguar)"]

        # repairs, newest first (the demo's power_up, stop_node, start_node started in turn)
        assert await page.evaluate(
            "[...document.querySelectorAll('#repairs .what')].map(e => e.textContent)") == [
            "start_node(jaguar_node)", "stop_node(jaguar_node)", "power_up(jaguar)"]

        # what is out of repair, and what a person does about it
        rows = await page.evaluate(
            "[...document.querySelectorAll('#out-of-repair .aside')].map(r =>"
            " [r.dataset.component, r.dataset.state, r.querySelector('.why').textContent,"
            "  r.querySelector('.release code').textContent])")
        assert rows == [
            ["hokuyo", "quarantined", "3 attempts in 10 min failed; left in safe state "
             "shutdown(hokuyo)", "dxboard quarantine clear hokuyo"],
            ["jaguar", "held", "switched off on the board by a command this daemon did not "
             "send", "switch it on again (dxboard board tcp://127.0.0.1:7000 on jaguar), or "
             "dxboard hold release jaguar"]]
        assert await page.evaluate("document.getElementById('out-of-repair-count')"
                                   ".textContent") == "2"
        source.update(out_of_repair=(), updated=time.time())
        assert await page.wait_for("document.querySelector('#out-of-repair .muted')"
                                   "?.textContent === 'nothing quarantined or held'")


async def test_screenshot_of_the_page_is_a_png(server: WebServer, tmp_path: Path) -> None:
    async with Chromium.launch(f"http://127.0.0.1:{server.port}/", width=1000) as page:
        await page.wait_for("document.querySelectorAll('.channel').length === 10")
        shot = tmp_path / "page.png"
        await page.screenshot(shot)
    assert shot.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
