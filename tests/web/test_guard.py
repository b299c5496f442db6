"""Who may read the page's data: Origin and Host checks, bad queries, clients that go away.

A web page the operator visits elsewhere must not read the robot's status over a cross-site
WebSocket, nor through DNS rebinding (a stranger's name resolving to the robot, so the browser
sends ``Host: stranger.example``). Every refusal is a 403 naming the reason; every bad query
parameter a 400 naming it; a client that hangs up mid-answer is a debug line, never a traceback.
The clients are aiohttp's client and raw sockets: no code shared with the server's guard.
"""

from __future__ import annotations

import asyncio
import logging
import socket
import struct
import subprocess
import sys
from collections.abc import AsyncIterator
from pathlib import Path

import aiohttp
import pytest

from host.journal import Journal
from host.web import MemoryStatusSource, WebServer

ROOT = Path(__file__).resolve().parents[2]


def url(server: WebServer, path: str) -> str:
    return f"http://127.0.0.1:{server.port}{path}"


async def fetch(server: WebServer, path: str, headers: dict[str, str]) -> tuple[int, str]:
    async with aiohttp.ClientSession() as s, s.get(url(server, path), headers=headers) as resp:
        return resp.status, await resp.text()


async def test_a_cross_site_websocket_is_refused_with_the_reason(server: WebServer) -> None:
    async with aiohttp.ClientSession() as s:
        with pytest.raises(aiohttp.WSServerHandshakeError) as refused:
            await s.ws_connect(url(server, "/ws"), origin="http://evil.example")
        assert refused.value.status == 403
        async with s.get(url(server, "/ws"), headers={"Origin": "http://evil.example"}) as resp:
            assert resp.status == 403
            assert "evil.example" in await resp.text() and "--web-allow-origin" in (
                await resp.text())
        for origin in (f"http://127.0.0.1:{server.port}", f"http://localhost:{server.port}"):
            async with s.ws_connect(url(server, "/ws"), origin=origin,
                                    headers={"Host": origin.split("//")[1]}) as ws:
                first = await ws.receive_json(timeout=30)
                assert first["type"] == "status"


async def test_api_with_a_strangers_host_header_is_refused(server: WebServer) -> None:
    status, text = await fetch(server, "/api/status", {"Host": f"evil.example:{server.port}"})
    assert status == 403 and "evil.example" in text
    status, text = await fetch(server, "/api/journal", {"Host": "rebound.example"})
    assert status == 403
    for host in (f"localhost:{server.port}", f"127.0.0.1:{server.port}", "localhost"):
        status, _ = await fetch(server, "/api/status", {"Host": host})
        assert status == 200, host
    status, text = await fetch(server, "/api/status", {"Origin": "http://evil.example"})
    assert status == 403


async def test_allowed_origins_name_other_pages_and_names(
        source: MemoryStatusSource, journal: Journal) -> None:
    web = WebServer(source, journal.reader,
                    allow_origins=("http://robot7.local:9000", "https://grafana.example"))
    await web.start("127.0.0.1", 0)
    try:
        assert (await fetch(web, "/api/status", {"Origin": "https://grafana.example"}))[0] == 200
        assert (await fetch(web, "/api/status", {"Host": "robot7.local:9000"}))[0] == 200
        assert (await fetch(web, "/api/status", {"Origin": "http://grafana.example"}))[0] == 403
        assert (await fetch(web, "/api/status", {"Host": "grafana.example.evil"}))[0] == 403
    finally:
        await web.close()


def test_policy_for_each_kind_of_listen_address() -> None:
    from host.web.guard import AccessPolicy

    loop = AccessPolicy("127.0.0.1")
    assert loop.refusal("localhost:8080", None) is None
    assert loop.refusal("[::1]:8080", "http://[::1]:8080") is None
    assert loop.refusal("192.168.0.7:8080", None) is not None
    assert loop.refusal(None, None) is not None  # HTTP/1.1 requires Host
    one = AccessPolicy("192.168.0.7")
    assert one.refusal("192.168.0.7:8080", "http://192.168.0.7:8080") is None
    assert one.refusal("robot.example:8080", None) is not None
    every = AccessPolicy("0.0.0.0")
    assert every.refusal("10.1.2.3:8080", "http://10.1.2.3:8080") is None
    assert every.refusal(f"{socket.gethostname()}:8080", None) is None
    assert every.refusal("evil.example:8080", None) is not None
    assert every.refusal("10.1.2.3:8080", "http://10.9.9.9:8080") is not None
    with pytest.raises(ValueError):
        AccessPolicy("127.0.0.1", ("not an origin",))


@pytest.mark.parametrize("query", [
    "since=99999999999999999999", "limit=99999999999999999999", "since=1e3", "limit=",
    "kind=", "since=1&since=2", "bogus=1",
])
async def test_every_bad_journal_query_is_a_400_with_the_reason(server: WebServer,
                                                                query: str) -> None:
    async with aiohttp.ClientSession() as s, s.get(url(server, f"/api/journal?{query}")) as resp:
        assert resp.status == 400
        assert (await resp.json())["error"]


async def test_unknown_query_parameters_elsewhere_are_a_400(server: WebServer) -> None:
    for path, name in (("/api/status?x=1", "'x'"), ("/metrics?name[]=a", "'name[]'"),
                       ("/ws?since=3", "'since'")):
        status, text = await fetch(server, path, {})
        assert status == 400 and name in text, (path, status, text)


async def hang_up(port: int, path: str, upgrade: bool, wait_s: float) -> None:
    _, writer = await asyncio.open_connection("127.0.0.1", port)
    head = f"GET {path} HTTP/1.1\r\nHost: 127.0.0.1:{port}\r\n"
    if upgrade:
        head += ("Upgrade: websocket\r\nConnection: Upgrade\r\nSec-WebSocket-Version: 13\r\n"
                 "Sec-WebSocket-Key: dGhlIHNhbXBsZSBub25jZQ==\r\n")
    writer.write((head + "\r\n").encode())
    await writer.drain()
    if wait_s:
        await asyncio.sleep(wait_s)
    sock = writer.get_extra_info("socket")  # close with a reset, as a killed browser does
    sock.setsockopt(socket.SOL_SOCKET, socket.SO_LINGER, struct.pack("ii", 1, 0))
    writer.close()


@pytest.fixture
async def busy_server(source: MemoryStatusSource,
                      journal: Journal) -> AsyncIterator[WebServer]:
    web = WebServer(source, journal.reader, push_interval_s=0.01, heartbeat_s=0.5)
    await web.start("127.0.0.1", 0)
    yield web
    await web.close()


async def test_clients_that_go_away_are_debug_lines_not_tracebacks(
        busy_server: WebServer, caplog: pytest.LogCaptureFixture) -> None:
    caplog.set_level(logging.DEBUG)
    for i in range(20):
        for path, upgrade in (("/ws", True), ("/api/journal?limit=1000", False), ("/", False)):
            await hang_up(busy_server.port, path, upgrade, 0.02 * (i % 3))
    # the server is still answering, and nothing it logged carries a traceback
    status, _ = await fetch(busy_server, "/api/status", {})
    assert status == 200
    loud = [r for r in caplog.records if r.exc_info or r.levelno >= logging.WARNING]
    assert not loud, [r.getMessage() for r in loud]


def test_a_bad_allowed_origin_is_one_line_and_exit_code_2(tmp_path: Path) -> None:
    out = subprocess.run([sys.executable, "-m", "host.cli", "run", "models/tedusar",
                          "--emulate", "--journal", str(tmp_path / "j.sqlite"),
                          "--web-allow-origin", "robot7.local"], cwd=ROOT, text=True,
                         capture_output=True, timeout=120)
    assert out.returncode == 2 and "Traceback" not in out.stderr
    assert out.stderr.strip().count("\n") == 0 and "--web-allow-origin" in out.stderr
