"""The JSON API, the metrics and the WebSocket push, over real HTTP against a real server.

The server is fed by ``MemoryStatusSource`` (the real implementation the daemon may use) and a
real journal; the tests change the status and the journal and watch what clients receive.
"""

from __future__ import annotations

import asyncio
import json
import time
from typing import Any

import aiohttp
import pytest

from host.errors import UserError
from host.journal import Journal, Note
from host.web import MemoryStatusSource, WebServer, parse_listen


def url(server: WebServer, path: str) -> str:
    return f"http://127.0.0.1:{server.port}{path}"


async def get_json(server: WebServer, path: str, status: int = 200) -> Any:
    async with aiohttp.ClientSession() as s, s.get(url(server, path)) as resp:
        assert resp.status == status
        return await resp.json()


async def test_status_has_channels_observations_diagnoses_and_repairs(
        server: WebServer) -> None:
    body = await get_json(server, "/api/status")
    assert len(body["channels"]) == 10
    hokuyo = body["channels"][3]
    assert {k: hokuyo[k] for k in ("id", "name", "on", "state", "current_ma")} == {
        "id": 3, "name": "hokuyo", "on": True, "state": "on", "current_ma": 640.0}
    assert body["observations"]["ok(jaguar_node)"] is False
    assert body["observations"]["current_ok(jaguar)"] is None
    assert body["diagnoses"][0]["bad"] == ["jaguar_node"]
    repair = body["repairs"][0]
    assert set(repair) >= {"action", "args", "state", "started", "finished"}
    assert (repair["action"], repair["args"], repair["state"]) == ("power_up", ["jaguar"],
                                                                   "succeeded")
    assert body["stale"] is False and body["board_link_up"] is True


async def test_status_is_stale_when_the_daemons_data_is_old(
        server: WebServer, source: MemoryStatusSource) -> None:
    source.update(updated=time.time() - 60)
    assert (await get_json(server, "/api/status"))["stale"] is True


async def test_journal_api_tail_since_kind_and_errors(server: WebServer,
                                                      journal: Journal) -> None:
    tail = await get_json(server, "/api/journal?limit=3")
    assert [e["id"] for e in tail["entries"]] == [11, 12, 13]
    assert tail["entries"][-1]["summary"] == "start_node(jaguar_node) started"
    since = await get_json(server, "/api/journal?since=10&limit=2")
    assert [e["id"] for e in since["entries"]] == [11, 12] and since["last_id"] == 12
    actions = await get_json(server, "/api/journal?since=0&kind=action,plan")
    assert {e["kind"] for e in actions["entries"]} == {"action", "plan"}
    assert len(actions["entries"]) == 7
    empty = await get_json(server, "/api/journal?since=13")
    assert empty == {"entries": [], "last_id": 13}
    for bad in ("since=-1", "limit=0", "limit=5000", "kind=bogus", "since=x"):
        assert "error" in await get_json(server, f"/api/journal?{bad}", status=400)


async def test_journal_api_without_a_journal_says_how_to_get_one(
        source: MemoryStatusSource) -> None:
    web = WebServer(source)
    await web.start("127.0.0.1", 0)
    try:
        body = await get_json(web, "/api/journal", status=404)
        assert "--journal" in body["error"]
    finally:
        await web.close()


async def test_websocket_pushes_each_change_and_new_journal_entries(
        server: WebServer, source: MemoryStatusSource, journal: Journal) -> None:
    async with aiohttp.ClientSession() as s, s.ws_connect(url(server, "/ws")) as ws:
        first = json.loads(await ws.receive_str(timeout=30))
        assert first["type"] == "status" and len(first["status"]["channels"]) == 10
        tail = json.loads(await ws.receive_str(timeout=30))
        assert tail["type"] == "journal" and tail["entries"][-1]["id"] == 13

        source.update_channel(6, state="on", on=True, current_ma=1234.0)
        journal.record(Note("thermal camera reset"), wall=time.time(), mono=5000.0)
        got_status = got_note = False
        for _ in range(50):
            msg = json.loads(await ws.receive_str(timeout=30))
            if msg["type"] == "status" and msg["status"]["channels"][6]["state"] == "on":
                assert msg["status"]["channels"][6]["current_ma"] == 1234.0
                assert msg["status"]["channels"][6]["history_ma"][-1] == 1234.0
                got_status = True
            if msg["type"] == "journal" and any(
                    e["data"].get("text") == "thermal camera reset" for e in msg["entries"]):
                got_note = True
            if got_status and got_note:
                break
        assert got_status and got_note
        await ws.send_str("please power off everything")  # read-only: ignored
        heartbeat = json.loads(await ws.receive_str(timeout=30))  # still served
        assert heartbeat["type"] == "status"
    assert source.snapshot().channels[0].on is True


async def test_nothing_can_be_changed_over_http(server: WebServer) -> None:
    async with aiohttp.ClientSession() as s:
        for path in ("/api/status", "/api/journal", "/metrics", "/"):
            async with s.post(url(server, path), data=b"{}") as resp:
                assert resp.status == 405


async def test_the_default_bind_is_localhost_only(source: MemoryStatusSource) -> None:
    assert parse_listen("8080") == ("127.0.0.1", 8080)
    assert parse_listen(":9000") == ("127.0.0.1", 9000)
    assert parse_listen("0.0.0.0:80") == ("0.0.0.0", 80)
    assert parse_listen("[::1]:81") == ("::1", 81)
    for bad in ("host:", "host:99999", "nonsense"):
        with pytest.raises(UserError):
            parse_listen(bad)
    web = WebServer(source)
    port = await web.start(port=0)
    try:
        assert web._runner is not None
        assert [a[0] for a in web._runner.addresses] == ["127.0.0.1"]
        other = WebServer(source)
        with pytest.raises(UserError, match="choose another port"):
            await other.start(port=port)
    finally:
        await web.close()


async def test_memory_source_wakes_waiters_and_keeps_channel_history() -> None:
    from tests.web.demo import demo_status

    source = MemoryStatusSource(demo_status(0.0))
    version = source.snapshot().version
    waiter = asyncio.create_task(source.wait_changed(version))
    await asyncio.sleep(0)
    assert not waiter.done()
    source.update_channel(3, current_ma=700.0, history_len=5)
    status = await asyncio.wait_for(waiter, 30)
    assert status.version == version + 1
    assert status.channels[3].history_ma[-1] == 700.0 and len(status.channels[3].history_ma) == 5
    with pytest.raises(KeyError):
        source.update_channel(42, current_ma=1.0)
