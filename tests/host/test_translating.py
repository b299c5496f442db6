"""The translating transports against ``dxboard emulate`` (a subprocess): Modbus TCP (pymodbus
against the firmware's Modbus server) and CAN over python-can's udp_multicast bus (a reboot
seen as a new nonce). The tug transport's tests are ``test_tug_*.py``."""

from __future__ import annotations

import asyncio
import json
import random
import time
from collections.abc import Callable, Iterator
from pathlib import Path

import pytest

from host.board import BoardClient, Reading, Rebooted
from host.commands.inject import request
from host.transports import open_transport
from host.transports.errors import AuthRefused, BadUrl, BoardRefused, NotSupported
from host.transports.modbus import ModbusTransport
from host.transports.url import parse
from protocol.constants import ST_OFF, ST_ON
from tests.host.emulate import KEY_HEX, Emulate
from tests.ports import reserved_udp_port
from tests.wait import wait_until_async

KEY = bytes.fromhex(KEY_HEX)


@pytest.fixture(scope="module")
def emu() -> Iterator[Emulate]:
    e = Emulate("--modbus", "127.0.0.1:0")
    yield e
    e.stop()


async def physical(client: BoardClient, channel: int) -> bool:
    return (await client.state()).channels[channel].physical


async def on_and_drawing(client: BoardClient, channel: int) -> bool:
    """The channel is on (inrush over) and draws current."""
    ch = (await client.state()).channels[channel]
    return ch.state == ST_ON and ch.current_ma > 0


async def readings_until(client: BoardClient, rate: int,
                         done: Callable[[Reading], bool]) -> list[Reading]:
    """Readings from a new subscription, up to the first for which ``done`` holds."""
    out: list[Reading] = []
    async for item in client.subscribe(rate):
        if isinstance(item, Reading):
            out.append(item)
            if done(item):
                break
    return out


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
        await wait_until_async(lambda: on_and_drawing(native, 5), what="router on")
        t0 = time.monotonic()
        a, b = await native.state(), await mb.state()
        apart_ms = (time.monotonic() - t0) * 1000  # a busy machine may take long between
        assert [c.state for c in a.channels] == [c.state for c in b.channels]
        assert b.channels[5].physical and b.channels[5].current_ma > 0
        assert abs(a.uptime_ms - b.uptime_ms) < 1000 + apart_ms
        got = await first_readings(mb, 5, 20)
        assert [r.seq for r in got] == [1, 2, 3, 4, 5]  # polled, numbered by the host
        assert all(r.on_mask & (1 << 5) for r in got)
        # writes are refused until the board's config allows this client
        with pytest.raises(BoardRefused, match="Modbus writes are not enabled"):
            await mb.switch(5, False)
        assert (await native.state()).channels[5].commanded
        await native.configurator.set_board_config(modbus_write=True, modbus_allow=[0x7F000001])
        res = await mb.switch(5, False)
        assert not res.physical and res.state == ST_OFF
        assert not (await native.state()).channels[5].commanded
        cyc = await mb.power_cycle(5, 0.2)  # off, wait, on by the host
        assert not cyc.physical
        await wait_until_async(lambda: physical(native, 5), what="router on again")
        with pytest.raises(NotSupported, match="not possible over modbus"):
            await mb.configurator.get_board_config()
        await native.configurator.set_board_config(modbus_write=False, modbus_allow=[])


async def test_a_reboot_over_modbus_is_told_by_the_boards_boot_id() -> None:
    """The boot id registers (110-111) carry the HELLO's boot id: the Modbus link has the
    board's own, and a watchdog reset is a new one (not an uptime that went backwards)."""
    e = Emulate("--modbus", "127.0.0.1:0")  # its own board: this one reboots
    try:
        async with BoardClient(e.urls["board"], KEY) as native, \
                BoardClient(e.urls["modbus"]) as mb:
            assert native.info is not None and mb.info is not None
            boot = native.info.boot_id
            assert mb.info.boot_id == boot != 0
            assert "boot_id" in mb.info.transport_caps
            items: list[object] = []

            async def consume() -> None:
                async for item in mb.subscribe(10):
                    items.append(item)

            task = asyncio.create_task(consume())
            try:
                await wait_until_async(lambda: any(isinstance(x, Reading) for x in items),
                                       what="a reading over Modbus")
                request(e.urls["control"], {"op": "inject", "channel": "board",
                                            "fault": "wdt_reset", "params": {}})
                await wait_until_async(lambda: any(isinstance(x, Rebooted) for x in items),
                                       what="the reboot seen over Modbus")
            finally:
                task.cancel()
            reboot = next(x for x in items if isinstance(x, Rebooted))
            assert reboot.how == "boot id" and reboot.old_boot_id == boot
            assert reboot.new_boot_id not in (boot, 0)
            assert reboot.reset_cause_name == "watchdog"
    finally:
        e.stop()


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
def can_emu(monkeypatch: pytest.MonkeyPatch) -> Iterator[Emulate]:
    # Linux hands a multicast datagram to every socket bound to its port, whatever group it
    # joined: a port of its own (python-can takes it from $CAN_CONFIG) keeps a second copy
    # of the suite off this bus; the group is random too.
    group = f"239.74.{random.randrange(1, 250)}.{random.randrange(1, 250)}"
    with reserved_udp_port() as port:
        config = json.dumps({"port": port})
        monkeypatch.setenv("CAN_CONFIG", config)  # this process's end, the host's transport
        e = Emulate("--can", f"udp_multicast:{group}", env={"CAN_CONFIG": config})
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
        # the readings follow the switch: the channel frames it reads come once a second
        got = await asyncio.wait_for(readings_until(
            c, 10, lambda r: bool(r.on_mask & (1 << 4)) and r.currents_ma[4] > 0), 60)
        assert [r.seq for r in got] == list(range(1, len(got) + 1))  # numbered by the host
        cyc = await c.power_cycle(4, 0.3)  # timed by the board
        assert not cyc.physical
        items: list[object] = []

        async def consume() -> None:
            async for item in c.subscribe(10):
                items.append(item)

        task = asyncio.create_task(consume())
        request(can_emu.urls["control"], {"op": "inject", "channel": "board",
                                          "fault": "wdt_reset", "params": {}})
        await wait_until_async(lambda: any(isinstance(x, Rebooted) for x in items),
                               what="the reboot seen over CAN")
        task.cancel()
        reboot = next(x for x in items if isinstance(x, Rebooted))
        assert reboot.how == "boot id" and reboot.reset_cause_name == "watchdog"
