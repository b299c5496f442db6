"""The translating transports against ``dxboard emulate`` (a subprocess): Modbus TCP (pymodbus
against the firmware's Modbus server) and CAN over python-can's udp_multicast bus (a reboot
seen as a new nonce). The tug transport's tests are ``test_tug_*.py``."""

from __future__ import annotations

import asyncio
import json
import random
from collections.abc import Iterator
from pathlib import Path

import pytest

from host.board import BoardClient, Reading, Rebooted
from host.commands.inject import request
from host.transports import open_transport
from host.transports.errors import AuthRefused, BadUrl, BoardRefused, NotSupported
from host.transports.modbus import ModbusTransport
from host.transports.url import parse
from protocol.constants import ST_OFF
from tests.host.emulate import KEY_HEX, Emulate

KEY = bytes.fromhex(KEY_HEX)


@pytest.fixture(scope="module")
def emu() -> Iterator[Emulate]:
    e = Emulate("--modbus", "127.0.0.1:0")
    yield e
    e.stop()


async def first_readings(client: BoardClient, n: int, rate: int) -> list[Reading]:
    out: list[Reading] = []
    async for item in client.subscribe(rate):
        if isinstance(item, Reading):
            out.append(item)
            if len(out) == n:
                return out
    return out


async def test_modbus_reads_the_same_board(emu: Emulate) -> None:
    async with BoardClient(emu.urls["board"], KEY) as native, \
            BoardClient(emu.urls["modbus"]) as mb:
        assert mb.info is not None and mb.info.channels == 10 and mb.info.version == 1
        await native.switch("router", True)
        await asyncio.sleep(0.3)
        a, b = await native.state(), await mb.state()
        assert [c.state for c in a.channels] == [c.state for c in b.channels]
        assert b.channels[5].physical and b.channels[5].current_ma > 0
        assert abs(a.uptime_ms - b.uptime_ms) < 1000
        got = await first_readings(mb, 5, 20)
        assert [r.seq for r in got] == [1, 2, 3, 4, 5]  # polled, numbered by the host
        assert all(r.on_mask & (1 << 5) for r in got)
        # writes are refused until the board's config allows this client
        with pytest.raises(BoardRefused, match="Modbus writes are not enabled"):
            await mb.switch(5, False)
        assert (await native.state()).channels[5].commanded
        await native.set_board_config(modbus_write=True, modbus_allow=[0x7F000001])
        res = await mb.switch(5, False)
        assert not res.physical and res.state == ST_OFF
        assert not (await native.state()).channels[5].commanded
        cyc = await mb.power_cycle(5, 0.2)  # off, wait, on by the host
        assert not cyc.physical
        await asyncio.sleep(0.5)
        assert (await native.state()).channels[5].physical
        with pytest.raises(NotSupported, match="not possible over modbus"):
            await mb.get_board_config()
        await native.set_board_config(modbus_write=False, modbus_allow=[])


def test_modbus_map_file(tmp_path: Path) -> None:
    good = tmp_path / "relay.json"
    good.write_text(json.dumps({"channels": 4, "switch_coils": 16}))
    t = open_transport(f"modbus+tcp://127.0.0.1:502?map={good}&unit=7")
    assert isinstance(t, ModbusTransport) and t.SCHEME == "modbus+tcp"
    rtu = open_transport("modbus+rtu:///dev/ttyUSB0?baud=9600&unit=3")
    assert isinstance(rtu, ModbusTransport) and rtu.SCHEME == "modbus+rtu" and rtu.unit == 3
    assert t.map == {"channels": 4, "switch_coils": 16} and t.unit == 7
    bad = tmp_path / "bad.json"
    bad.write_text(json.dumps({"channels": 4, "coils": 0}))
    with pytest.raises(BadUrl, match="unknown key"):
        ModbusTransport(parse(f"modbus+tcp://127.0.0.1:502?map={bad}"))
    with pytest.raises(BadUrl, match="unknown parameter 'baud'"):
        ModbusTransport(parse("modbus+tcp://127.0.0.1:502?baud=9600"))


@pytest.fixture
def can_emu() -> Iterator[Emulate]:
    group = f"239.74.{random.randrange(1, 250)}.{random.randrange(1, 250)}"
    e = Emulate("--can", f"udp_multicast:{group}")
    yield e
    e.stop()


async def test_can_over_udp_multicast(can_emu: Emulate) -> None:
    url = can_emu.urls["can"]
    assert url.startswith("can://udp_multicast/")
    async with BoardClient(url + "?node=0", b"wrong key") as bad:
        with pytest.raises(AuthRefused, match="bad authentication tag"):
            await bad.switch(4, True)
    async with BoardClient(can_emu.urls["board"], KEY) as native:
        assert not (await native.state()).channels[4].commanded  # refused: no change
    async with BoardClient(url, KEY) as c:
        assert c.info is not None and c.info.channels == 10
        res = await c.switch(4, True)
        assert res.physical and res.commanded
        got = await first_readings(c, 3, 10)
        assert [r.seq for r in got] == [1, 2, 3] and all(r.on_mask & (1 << 4) for r in got)
        assert got[-1].currents_ma[4] > 0
        cyc = await c.power_cycle(4, 0.3)  # timed by the board
        assert not cyc.physical
        items: list[object] = []

        async def consume() -> None:
            async for item in c.subscribe(10):
                items.append(item)

        task = asyncio.create_task(consume())
        request(can_emu.urls["control"], {"op": "inject", "channel": "board",
                                          "fault": "wdt_reset", "params": {}})
        for _ in range(100):
            await asyncio.sleep(0.05)
            if any(isinstance(x, Rebooted) for x in items):
                break
        task.cancel()
        reboot = next(x for x in items if isinstance(x, Rebooted))
        assert reboot.how == "boot id" and reboot.reset_cause_name == "watchdog"
