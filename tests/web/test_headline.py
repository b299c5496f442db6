"""The page's headline and the status's verdict: healthy, repairing, needs you, unknown, behind.

Issue 26 item 6 (the page had no line saying whether the robot is healthy) and issue 25 item 6
(unknown is not healthy; a daemon that falls behind says so). Read from ``/api/status`` over
real HTTP and from the page in real headless Chromium.
"""

from __future__ import annotations

import time
from typing import Any

import aiohttp

from host.web import MemoryStatusSource, OutOfRepair, WebServer
from tests.web.chromium import Chromium
from tests.web.demo import kept_fresh

HEADLINE = "document.querySelector('#headline')"


async def status(server: WebServer) -> Any:
    async with aiohttp.ClientSession() as s, \
            s.get(f"http://127.0.0.1:{server.port}/api/status") as resp:
        assert resp.status == 200
        return await resp.json()


async def head(server: WebServer) -> tuple[str, str]:
    h = (await status(server))["headline"]
    return h["state"], h["text"]


async def test_each_verdict_from_the_status(server: WebServer,
                                            source: MemoryStatusSource) -> None:
    now = time.time()
    source.update(updated=now, diagnosed_at=now)
    assert await head(server) == ("repairing", "repairing jaguar_node")
    source.update(diagnoses=(), repairs=())
    assert await head(server) == ("healthy", "healthy")
    source.update(unknown=("hokuyo_node", "hector_mapping"))
    state, text = await head(server)
    assert state == "unknown" and "hokuyo_node, hector_mapping" in text
    assert "healthy" not in text
    source.update(unknown=(), out_of_repair=(OutOfRepair(
        "hokuyo", "quarantined", "3 repair attempts", "daemon", now,
        "dxboard quarantine clear hokuyo"),))
    state, text = await head(server)
    assert state == "needs_you" and "dxboard quarantine clear hokuyo" in text
    source.update(out_of_repair=(), board_link_up=False)
    assert await head(server) == ("needs_you", "needs you: board link down")


async def test_a_daemon_that_stopped_diagnosing_says_it_is_behind(
        server: WebServer, source: MemoryStatusSource) -> None:
    now = time.time()
    source.update(updated=now, diagnosed_at=now - 150.0, diagnoses=(), repairs=())
    body = await status(server)
    assert body["behind"] is True and body["diagnosis_age_s"] >= 150.0
    state, text = body["headline"]["state"], body["headline"]["text"]
    assert state == "behind" and "150 s" in text
    source.update(diagnosed_at=now)
    assert (await status(server))["behind"] is False


async def test_the_page_says_at_the_top_whether_the_robot_is_healthy(
        server: WebServer, source: MemoryStatusSource) -> None:
    source.update(diagnoses=(), repairs=(), diagnosed_at=time.time() + 3600)  # never behind
    async with kept_fresh(source), Chromium.launch(f"http://127.0.0.1:{server.port}/") as page:
        assert await page.wait_for(f"{HEADLINE}.textContent === 'healthy'", 60)
        source.update(unknown=("hokuyo_node",))
        assert await page.wait_for(f"{HEADLINE}.dataset.state === 'unknown'", 60)
        assert "hokuyo_node" in await page.evaluate(f"{HEADLINE}.textContent")
        assert "hokuyo_node" in await page.evaluate(
            "document.querySelector('#diagnoses .unknown').textContent")
        source.update(unknown=(), board_link_up=False)
        assert await page.wait_for(f"{HEADLINE}.textContent === 'needs you: board link down'",
                                   60)


async def test_a_journal_that_cannot_write_needs_you_with_the_entries_it_holds(
        server: WebServer, source: MemoryStatusSource) -> None:
    now = time.time()
    source.update(updated=now, diagnosed_at=now, diagnoses=(), repairs=(),
                  journal_problem="disk full", journal_held=12)
    body = await status(server)
    assert body["journal"] == {"problem": "disk full", "held": 12, "dropped": 0}
    assert (body["headline"]["state"], body["headline"]["text"]) == (
        "needs_you", "needs you: journal: disk full, 12 entries held")
    source.update(journal_problem="", journal_held=0)
    assert await head(server) == ("healthy", "healthy")
