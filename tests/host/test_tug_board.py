"""Our ``tug://`` client against our own board's tug front end (``dxboard emulate --tug``), and
the front end's safety as a person meets it: read-only unless ``--tug-switch``, protected
channels never switched off, at most two links (a new one closes the oldest), a reboot closes
them, and ``--tug-switch`` alone is one line and exit 2."""

from __future__ import annotations

import json
import socket
import subprocess
import sys
from collections.abc import Iterator

import pytest

from host.board import BoardClient, Reading
from host.commands.inject import request
from host.transports.errors import BoardRefused, NotSupported
from protocol import tug as tw
from tests.host.emulate import ENV, KEY_HEX, ROOT, Emulate

KEY = bytes.fromhex(KEY_HEX)


@pytest.fixture(scope="module")
def emu() -> Iterator[Emulate]:
    e = Emulate("--tug", "127.0.0.1:0", "--tug-switch")
    yield e
    e.stop()


def address(url: str) -> tuple[str, int]:
    host, _, port = url.removeprefix("tug://").rpartition(":")
    return host, int(port)


def read_frames(sock: socket.socket, want: int) -> list[tw.Frame]:
    """Frames from a raw socket until ``want`` arrived or the board closed the link."""
    d = tw.TugDecoder(tw.FROM_BOARD)
    out: list[tw.Frame] = []
    while len(out) < want:
        data = sock.recv(4096)
        if not data:
            break
        d.feed(data)
        out += [f for f in d.frames() if isinstance(f, tw.Frame)]
    return out


def closed_by_board(sock: socket.socket) -> bool:
    """True once the board closed the link (it sends nothing unasked before SET FREQUENCY)."""
    try:
        while sock.recv(4096):
            pass
    except TimeoutError:
        return False
    except ConnectionResetError:
        pass
    return True


async def test_client_against_our_board(emu: Emulate) -> None:
    async with BoardClient(emu.urls["board"], KEY) as native, \
            BoardClient(emu.urls["tug"]) as tug:
        assert tug.info is not None and tug.info.channels == 10
        assert tug.info.board_id.startswith("tug@")
        res = await tug.switch(6, True)
        assert res.physical
        st = await native.state()
        assert st.channels[6].commanded and st.channels[6].physical
        tst = await tug.state()
        assert tst.channels[6].physical and tst.channels[6].current_ma > 0
        got: list[Reading] = []
        async for item in tug.subscribe(20):
            if isinstance(item, Reading):
                got.append(item)
                if len(got) == 2:
                    break
        assert [r.seq for r in got] == [1, 2] and got[0].input_mv == 22200
        assert all(r.on_mask & (1 << 6) for r in got)
        await tug.switch(6, False)
        assert not (await native.state()).channels[6].commanded
        with pytest.raises(BoardRefused, match="protected channels are not switched off"):
            await tug.switch(2, False)
        assert (await native.state()).channels[2].physical
        with pytest.raises(NotSupported):
            await tug.configurator.get_channel_config(6)


def test_read_only_unless_switching_is_asked_for() -> None:
    e = Emulate("--tug", "127.0.0.1:0")
    try:
        cmd = [sys.executable, "-m", "host.cli", "board", e.urls["tug"]]
        got = subprocess.run([*cmd, "on", "5"], cwd=ROOT, env=ENV, capture_output=True,
                             text=True, timeout=60)
        assert got.returncode == 2
        assert "switching over tug is not enabled on this board" in got.stderr
        assert len(got.stderr.strip().splitlines()) == 1, got.stderr
        status = subprocess.run([*cmd, "status", "--json"], cwd=ROOT, env=ENV,
                                capture_output=True, text=True, timeout=60)
        assert status.returncode == 0, status.stderr
        chans = json.loads(status.stdout)["state"]["channels"]
        assert not chans[5]["physical"] and chans[2]["physical"]  # reads, switched nothing
    finally:
        e.stop()


def test_tug_switch_needs_tug() -> None:
    got = subprocess.run([sys.executable, "-m", "host.cli", "emulate",
                          str(ROOT / "models" / "tedusar"), "--tug-switch"], cwd=ROOT, env=ENV,
                         capture_output=True, text=True, timeout=60)
    assert got.returncode == 2 and got.stdout == ""
    assert got.stderr.strip() == ("dxboard emulate: error: --tug-switch needs --tug H:P "
                                  "(add --tug 127.0.0.1:5000, say)")


def test_two_links_at_most_a_new_one_closes_the_oldest(emu: Emulate) -> None:
    socks = []
    try:
        for _ in range(3):
            s = socket.create_connection(address(emu.urls["tug"]), timeout=20)
            assert [f.command for f in read_frames(s, 1)] == [tw.SPECS]
            socks.append(s)
        assert closed_by_board(socks[0])
        for s in socks[1:]:
            s.settimeout(0.5)
            assert not closed_by_board(s)
            s.settimeout(20)
            s.sendall(tw.request())
            assert [f.command for f in read_frames(s, 2)] == [tw.ACK, tw.MEASUREMENTS]
    finally:
        for s in socks:
            s.close()


def test_a_reboot_closes_the_links() -> None:
    e = Emulate("--tug", "127.0.0.1:0")
    try:
        with socket.create_connection(address(e.urls["tug"]), timeout=20) as s:
            assert [f.command for f in read_frames(s, 1)] == [tw.SPECS]
            request(e.urls["control"], {"op": "inject", "channel": "board",
                                        "fault": "wdt_reset", "params": {}})
            assert closed_by_board(s)
    finally:
        e.stop()
