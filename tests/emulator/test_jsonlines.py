"""The one JSON-lines request/reply helper: a real asyncio server, a plain-socket client."""

from __future__ import annotations

import asyncio
import json
import socket
from pathlib import Path
from typing import Any

import pytest

from emulator.jsonlines import Lines, ask, connect_retrying, tcp_address

DEADLINE_S = 60.0


def _lines() -> tuple[Lines, list[Any]]:
    closed: list[Any] = []

    async def slow(msg: dict[str, Any], conn: Any) -> dict[str, Any]:
        await asyncio.sleep(0)
        return {"ok": True, "slow": msg["n"]}

    def boom(msg: dict[str, Any], conn: Any) -> dict[str, Any]:
        raise RuntimeError("the handler broke")

    def refuse(msg: dict[str, Any], conn: Any) -> dict[str, Any]:
        raise ValueError("give n as a number")

    lines = Lines({"echo": lambda m, c: {"ok": True, "echo": m.get("x")}, "slow": slow,
                   "boom": boom, "refuse": refuse, "quiet": lambda m, c: None},
                  max_line=1024, on_close=closed.append)
    return lines, closed


def test_answer_names_the_fix_for_bad_json_and_unknown_kinds() -> None:
    lines, _ = _lines()
    assert lines.answer(b"not json\n") == {"ok": False, "error": "not a JSON object on one line"}
    assert lines.answer(b"[1]\n") == {"ok": False, "error": "not a JSON object on one line"}
    assert lines.answer(b'{"op": "dance"}\n') == {
        "ok": False, "error": "unknown op 'dance' (echo, slow, boom, refuse, quiet)"}
    assert lines.answer(b'{"op": "refuse"}\n') == {"ok": False, "error": "give n as a number"}
    assert lines.answer(b'{"op": "echo", "x": 3}\n') == {"ok": True, "echo": 3}


def test_a_real_connection_gets_one_reply_per_line_and_survives_errors() -> None:
    async def main() -> None:
        lines, closed = _lines()
        server = await asyncio.start_server(lines.serve, "127.0.0.1", 0, limit=1024)
        port = server.sockets[0].getsockname()[1]
        try:
            reader, writer = await asyncio.wait_for(
                asyncio.open_connection("127.0.0.1", port), DEADLINE_S)
            for req in (b"junk\n", b'{"op": "boom"}\n', b'{"op": "quiet"}\n',
                        b'{"op": "slow", "n": 7}\n', b'{"op": "echo", "x": "y"}\n'):
                writer.write(req)
            await writer.drain()
            got = [json.loads(await asyncio.wait_for(reader.readline(), DEADLINE_S))
                   for _ in range(4)]  # "quiet" has no reply
            assert got == [{"ok": False, "error": "not a JSON object on one line"},
                           {"ok": False, "error": "failed: the handler broke"},
                           {"ok": True, "slow": 7}, {"ok": True, "echo": "y"}]
            writer.write(b"x" * 5000 + b"\n")  # over the cap: answered, then closed
            await writer.drain()
            last = json.loads(await asyncio.wait_for(reader.readline(), DEADLINE_S))
            assert last == {"ok": False, "error": "line too long"}
            assert await asyncio.wait_for(reader.read(), DEADLINE_S) == b""
            writer.close()
            # a client that goes away mid-line is ended quietly, and on_close hears of it
            _, w2 = await asyncio.open_connection("127.0.0.1", port)
            w2.write(b'{"op": "ec')
            await w2.drain()
            w2.transport.abort()
            loop = asyncio.get_running_loop()
            end = loop.time() + DEADLINE_S
            while len(closed) < 2 and loop.time() < end:
                await asyncio.sleep(0.01)
            assert len(closed) == 2
        finally:
            server.close()
            await server.wait_closed()

    asyncio.run(main())


def test_ask_over_a_unix_socket_and_a_refused_port(tmp_path: Path) -> None:
    path = tmp_path / "s.sock"
    lines, _ = _lines()
    with socket.socket(socket.AF_INET, socket.SOCK_STREAM) as free:
        free.bind(("127.0.0.1", 0))
        port = free.getsockname()[1]  # bound, not listening: refused
        with pytest.raises(OSError):
            ask(("127.0.0.1", port), {"op": "echo"}, DEADLINE_S)
    with pytest.raises(FileNotFoundError):
        ask(path, {"op": "echo"}, DEADLINE_S)

    async def main() -> None:
        server = await asyncio.start_unix_server(lines.serve, path=str(path))
        try:
            reply = await asyncio.to_thread(ask, path, {"op": "echo", "x": [1]}, DEADLINE_S)
            assert reply == {"ok": True, "echo": [1]}
        finally:
            server.close()
            await server.wait_closed()

    asyncio.run(main())


def test_connect_retrying_waits_for_a_late_server_gives_up_at_its_deadline_or_stop() -> None:
    async def main() -> None:
        loop = asyncio.get_running_loop()
        with socket.socket(socket.AF_INET, socket.SOCK_STREAM) as held:
            held.bind(("127.0.0.1", 0))  # bound, not listening: every try is refused
            address = held.getsockname()[:2]
            refusals: list[OSError] = []
            with pytest.raises(OSError):
                await connect_retrying(address, 0.01, deadline=loop.time() + 0.05,
                                       refused=refusals.append)
            assert len(refusals) >= 1
            stop = asyncio.Event()
            stop.set()
            assert await connect_retrying(address, 0.01, stop=stop) is None
            # the server appears while the client waits: it connects
            stop = asyncio.Event()
            trying = asyncio.ensure_future(connect_retrying(address, 0.01, stop=stop))
            await asyncio.sleep(0.05)
            assert not trying.done()
            held.listen()
            pair = await asyncio.wait_for(trying, DEADLINE_S)
            assert pair is not None
            pair[1].close()

    asyncio.run(main())


@pytest.mark.parametrize(("url", "address"), [
    ("tcp://127.0.0.1:7000", ("127.0.0.1", 7000)), ("tcp://[::1]:9", ("::1", 9)),
    ("http://127.0.0.1:7000", None), ("tcp://127.0.0.1", None), ("tcp://h:99999", None),
    ("tcp://:80", None)])
def test_tcp_address_reads_only_tcp_host_port(url: str, address: tuple[str, int] | None) -> None:
    assert tcp_address(url) == address
