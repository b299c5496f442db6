"""``dxboard board`` against ``dxboard emulate`` (subprocesses), over TCP and serial (a real pty
pair): the table for a person, ``--json`` for scripts, one-line errors, and a subscribed client
that lives through the emulator being killed and restarted."""

from __future__ import annotations

import asyncio
import json
import subprocess
import sys
from collections.abc import Iterator

import pytest

from host.board import BoardClient, LinkDown, LinkUp, Reading, Rebooted
from tests.host.emulate import ENV, KEY_HEX, ROOT, Emulate
from tests.ports import free_port
from tests.wait import wait_until, wait_until_async


@pytest.fixture(scope="module")
def emu() -> Iterator[Emulate]:
    e = Emulate("--serial")
    # the board's power-up queue switches pc on after boot: these tests start from there
    wait_until(lambda: json.loads(board(e.urls["board"], "status", "--json").stdout)
               ["state"]["channels"][2]["state"] == "on", what="pc on")
    yield e
    e.stop()


def board(url: str, *args: str, key: str | None = KEY_HEX) -> subprocess.CompletedProcess[str]:
    env = dict(ENV)
    env.pop("DXBOARD_KEY")
    if key is not None:
        env["DXBOARD_KEY"] = key
    return subprocess.run([sys.executable, "-m", "host.cli", "board", url, *args],
                          capture_output=True, text=True, timeout=60, env=env, cwd=ROOT)


@pytest.mark.parametrize("which", ["board", "serial"])
def test_status_table_and_json(emu: Emulate, which: str) -> None:
    url = emu.urls[which]
    done = board(url, "status")
    assert done.returncode == 0, done.stderr
    lines = done.stdout.splitlines()
    assert lines[0].startswith("board tedusar (firmware")
    assert lines[2].split() == ["CH", "NAME", "STATE", "CURRENT", "FAULTS"]
    assert lines[5].split()[:3] == ["2", "pc", "on"]  # pc powers up by itself
    done = board(url, "status", "--json")
    data = json.loads(done.stdout)
    assert data["board"]["board_id"] == "tedusar" and data["board"]["scheme"] in ("tcp", "serial")
    assert data["state"]["channels"][2]["name"] == "pc"
    assert data["state"]["channels"][2]["state"] in ("inrush", "on")


def test_on_off_by_name_and_wrong_key(emu: Emulate) -> None:
    url = emu.urls["board"]
    done = board(url, "on", "kinect", "--json")
    assert done.returncode == 0, done.stderr
    assert json.loads(done.stdout)["result"]["physical"] is True
    done = board(url, "off", "kinect", key="ffff")
    assert done.returncode == 2
    assert "bad authentication tag" in done.stderr and "Traceback" not in done.stderr
    assert done.stderr.count("\n") == 1
    state = json.loads(board(url, "status", "--json").stdout)["state"]
    assert state["channels"][4]["commanded"] is True  # the refused "off" changed nothing
    done = board(url, "off", "kinect")
    assert done.returncode == 0 and "is now off" in done.stdout


def test_config_get_set_and_watch(emu: Emulate) -> None:
    url = emu.urls["serial"]
    done = board(url, "config", "set", "spare8", "rated_ma=1500", "--json")
    assert done.returncode == 0, done.stderr
    assert json.loads(done.stdout)["rated_ma"] == 1500
    got = json.loads(board(url, "config", "get", "spare8", "--json").stdout)
    assert got["rated_ma"] == 1500 and got["name"] == "spare8"
    done = board(emu.urls["board"], "watch", "--count", "3", "--rate", "20", "--json")
    rows = [json.loads(x) for x in done.stdout.splitlines()]
    assert [r["seq"] for r in rows] == [1, 2, 3] and len(rows[0]["currents_ma"]) == 10


@pytest.mark.parametrize(("url", "expect"), [
    ("tcp://127.0.0.1:1", "cannot reach tcp://127.0.0.1:1"),
    ("gopher://x:1", "unknown board URL scheme 'gopher'"),
    ("serial:///dev/nonexistent-tty", "cannot reach serial:///dev/nonexistent-tty"),
])
def test_errors_are_one_line(url: str, expect: str) -> None:
    done = board(url, "status")
    assert done.returncode == 2
    assert expect in done.stderr and done.stderr.count("\n") == 1


def test_bad_channel_name(emu: Emulate) -> None:
    done = board(emu.urls["board"], "on", "hokuyoo")
    assert done.returncode == 2 and "no channel 'hokuyoo'" in done.stderr
    assert "hokuyo" in done.stderr  # the hint lists the names


async def test_emulator_killed_and_restarted_under_a_subscriber() -> None:
    port = free_port()
    first = Emulate("--listen", f"127.0.0.1:{port}", "--seed", "1")
    client = BoardClient(first.urls["board"], bytes.fromhex(KEY_HEX), backoff_s=0.1,
                         max_backoff_s=0.5)
    items: list[object] = []
    second = None
    try:
        await client.connect()

        async def consume() -> None:
            async for item in client.subscribe(20):
                items.append(item)

        task = asyncio.create_task(consume())
        await wait_until_async(lambda: sum(isinstance(x, Reading) for x in items) > 5,
                               what="readings from the first emulator")
        first.kill()
        await wait_until_async(lambda: any(isinstance(x, LinkDown) for x in items),
                               what="the link down")
        # the same port again: below the ephemeral range, nobody else is handed it meanwhile
        second = Emulate("--listen", f"127.0.0.1:{port}", "--seed", "2")
        await wait_until_async(lambda: any(isinstance(x, LinkUp) for x in items)
                               and isinstance(items[-1], Reading) and items[-1].seq >= 5,
                               what="readings from the restarted emulator",
                               show=lambda: items[-3:])
        task.cancel()
    finally:
        await client.close()
        first.kill()
        if second is not None:
            second.stop()
    kinds = [type(x) for x in items]
    down, up = kinds.index(LinkDown), kinds.index(LinkUp)
    assert down < kinds.index(Rebooted) < up
    before = [x for x in items[:down] if isinstance(x, Reading)]
    after = [x for x in items[down:] if isinstance(x, Reading)]
    assert items.index(after[0]) < up  # up once the new session is heard measuring
    assert [r.seq for r in before] == list(range(1, len(before) + 1)) and len(before) > 5
    assert after[0].seq == 1 and after[0].boot_id != before[0].boot_id
    assert all(r.missed == 0 for r in before + after)
