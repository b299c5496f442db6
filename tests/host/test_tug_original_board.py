"""Our ``tug://`` client against the original TEDUSAR board (``tug_board_peer``: Board.cpp byte
for byte): ``dxboard board tug://... on CH``, ``off``, ``status`` and ``watch`` as a person
runs them (a subprocess each), and ``BoardClient`` in-process.

The original board serves one client in its life (it dies of SIGPIPE when that client
leaves), so every command gets a fresh peer. It reads one command per ``recv``: the client
must never put two commands into one segment, which ``received`` shows.
"""

from __future__ import annotations

import json
import subprocess
import sys
from collections.abc import Iterator

import pytest

from host.board import BoardClient, Reading
from protocol.constants import ST_OFF, ST_ON
from tests.host.emulate import ENV, ROOT
from tests.host.tug_board_peer import OriginalBoard


@pytest.fixture
def peer() -> Iterator[OriginalBoard]:
    board = OriginalBoard()
    yield board
    board.close()


def dxboard(*args: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run([sys.executable, "-m", "host.cli", "board", *args], cwd=ROOT,
                          env=ENV, capture_output=True, text=True, timeout=60)


def one_command_per_recv(peer: OriginalBoard) -> None:
    """Every chunk the board read starts a frame and holds exactly one."""
    for chunk in peer.received:
        assert chunk[0] == 2, chunk.hex()
        length = chunk[2] | chunk[3] << 8
        assert len(chunk) == 4 + length, chunk.hex()


def test_cli_switches_off_and_on(peer: OriginalBoard) -> None:
    got = dxboard(peer.url, "off", "3")
    assert got.returncode == 0, got.stderr
    assert "did not answer" not in got.stderr
    assert peer.on_off[3] == 0 and peer.on_off[2] == 1
    one_command_per_recv(peer)
    again = OriginalBoard()
    try:
        got = dxboard(again.url, "off", "5")
        assert got.returncode == 0, got.stderr
        assert again.on_off[5] == 0
        on = OriginalBoard()
        try:
            on.on_off[5] = 0
            got = dxboard(on.url, "on", "5")
            assert got.returncode == 0, got.stderr
            assert on.on_off[5] == 1
        finally:
            on.close()
    finally:
        again.close()


def test_cli_status_reads_the_original_measurements(peer: OriginalBoard) -> None:
    got = dxboard(peer.url, "status", "--json")
    assert got.returncode == 0, got.stderr
    st = json.loads(got.stdout)
    chans = st["state"]["channels"]
    assert len(chans) == 8 and st["board"]["channels"] == 8
    # Board.cpp main(): every channel on, present current c + 1 + 0.1 c (even), c + 2 + 0.1 c
    assert [c["physical"] for c in chans] == [True] * 8
    assert [c["current_ma"] for c in chans] == [1000, 3100, 3200, 5300, 5400, 7500, 7600, 9700]
    one_command_per_recv(peer)


def test_cli_watch_gets_the_one_hertz_broadcast(peer: OriginalBoard) -> None:
    got = dxboard(peer.url, "watch", "--count", "3", "--json")
    assert got.returncode == 0, got.stderr
    readings = [json.loads(line) for line in got.stdout.splitlines()]
    assert [r["seq"] for r in readings] == [1, 2, 3]
    assert all(r["on_mask"] == 0xFF for r in readings)
    assert readings[0]["currents_ma"][7] == 9700
    assert peer.broadcasters == 1  # asked once: the original adds a broadcaster per ask
    one_command_per_recv(peer)


async def test_client_in_process(peer: OriginalBoard) -> None:
    async with BoardClient(peer.url) as c:
        assert c.info is not None and c.info.channels == 8
        assert c.info.board_id == f"tug@127.0.0.1:{peer.port}"
        res = await c.switch(6, False)
        assert not res.physical and res.state == ST_OFF and peer.on_off[6] == 0
        res = await c.switch(6, True)
        assert res.physical and res.state == ST_ON and peer.on_off[6] == 1
        st = await c.state()
        assert [round(ch.current_ma) for ch in st.channels][:2] == [1000, 3100]
        await c.ping()
        seen = []
        async for item in c.subscribe(50):
            if isinstance(item, Reading):
                seen.append(item)
                if len(seen) == 2:
                    break
        assert [r.seq for r in seen] == [1, 2]
    one_command_per_recv(peer)
