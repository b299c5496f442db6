"""dxboard's Modbus client against a device that is not our firmware: pymodbus's own server.

A relay board described by a map file works: status, on and off with the switch read back.
A device that looks wrong to the board's default map gets one line and exit 2, never a
traceback: a channel count of 0, no channel-count register (exception 02), a unit id it does
not serve (exception 04). A read-back that disagrees says which part disagrees.
"""

from __future__ import annotations

import asyncio
import json
import subprocess
import sys
import threading
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

import pytest
from pymodbus.client import ModbusTcpClient
from pymodbus.datastore import (
    ModbusDeviceContext,
    ModbusSequentialDataBlock,
    ModbusServerContext,
)
from pymodbus.server import ModbusTcpServer

from tests.host.emulate import ENV, ROOT


def block(values: list[int]) -> ModbusSequentialDataBlock:
    return ModbusSequentialDataBlock(1, values)  # pymodbus: block address 1 = protocol 0


class Device:
    """A pymodbus TCP server on its own loop in a thread (the CLI runs as a subprocess)."""

    def __init__(self, devices: dict[int, ModbusDeviceContext]) -> None:
        self.context = ModbusServerContext(devices=devices, single=False)
        self.loop = asyncio.new_event_loop()
        self.server: ModbusTcpServer | None = None
        self.port = 0
        ready = threading.Event()
        self.thread = threading.Thread(target=self._run, args=(ready,), daemon=True)
        self.thread.start()
        assert ready.wait(30), "the pymodbus server did not start"

    def _run(self, ready: threading.Event) -> None:
        asyncio.set_event_loop(self.loop)

        async def main() -> None:
            self.server = ModbusTcpServer(self.context, address=("127.0.0.1", 0))
            task = asyncio.ensure_future(self.server.serve_forever())
            while self.server.transport is None:
                await asyncio.sleep(0.01)
            self.port = self.server.transport.sockets[0].getsockname()[1]
            ready.set()
            await task

        self.loop.run_until_complete(main())

    @property
    def url(self) -> str:
        return f"modbus+tcp://127.0.0.1:{self.port}"

    def coils(self, unit: int, n: int) -> list[bool]:
        """The device's coils as a plain pymodbus client reads them."""
        client = ModbusTcpClient("127.0.0.1", port=self.port, timeout=30, retries=0)
        try:
            assert client.connect()
            reply = client.read_coils(0, count=n, device_id=unit)
            assert not reply.isError(), reply
            return [bool(b) for b in reply.bits[:n]]
        finally:
            client.close()

    def stop(self) -> None:
        if self.server is not None:
            asyncio.run_coroutine_threadsafe(self.server.shutdown(), self.loop).result(10)
        self.thread.join(10)


def dxboard(*args: str) -> subprocess.CompletedProcess[str]:
    env = {k: v for k, v in ENV.items() if k != "DXBOARD_KEY"}
    return subprocess.run([sys.executable, "-m", "host.cli", *args], capture_output=True,
                          text=True, timeout=60, env=env, cwd=ROOT)


def one_line_error(done: subprocess.CompletedProcess[str], *needles: str) -> None:
    assert done.returncode == 2, (done.stdout, done.stderr)
    assert "Traceback" not in done.stderr and done.stderr.count("\n") == 1, done.stderr
    for needle in needles:
        assert needle in done.stderr, done.stderr


def board_like(count: int = 10, ir_size: int = 110, readback: bool = True) -> ModbusDeviceContext:
    """Looks like our board's map from far away: input registers 0..ir_size-1, with the
    channel count in 108 and version 1 in 109 (when there)."""
    ir = [0] * ir_size
    if ir_size > 109:
        ir[108], ir[109] = count, 1
    return ModbusDeviceContext(co=block([0] * 16), di=block([0] * 32), ir=block(ir),
                               hr=block([0] * 16))


@pytest.fixture
def device() -> Iterator[Callable[..., Device]]:
    made: list[Device] = []

    def make(**kw: Any) -> Device:
        d = Device(**kw)
        made.append(d)
        return d

    yield make
    for d in made:
        d.stop()


def test_a_relay_board_described_by_a_map(device: Callable[..., Device],
                                          tmp_path: Path) -> None:
    relay = ModbusDeviceContext(co=block([0] * 8), di=block([0] * 8), ir=block([0] * 8),
                                hr=block([0] * 8))
    dev = device(devices={3: relay})
    relay_map = tmp_path / "relay.json"
    relay_map.write_text(json.dumps({"channels": 4, "switch_coils": 0,
                                     "current_registers": 0, "current_scale": 10}))
    url = f"{dev.url}?unit=3&map={relay_map}"
    done = dxboard("board", url, "status", "--json")
    assert done.returncode == 0, done.stderr
    state = json.loads(done.stdout)["state"]
    assert [c["state"] for c in state["channels"]] == ["off"] * 4
    done = dxboard("board", url, "on", "2", "--json")
    assert done.returncode == 0, done.stderr
    assert json.loads(done.stdout)["result"]["physical"] is True
    assert dev.coils(3, 4) == [False, False, True, False]
    done = dxboard("board", url, "off", "2")
    assert done.returncode == 0, done.stderr
    assert dev.coils(3, 4) == [False] * 4


def test_channel_count_zero(device: Callable[..., Device]) -> None:
    dev = device(devices={1: board_like(count=0)})
    one_line_error(dxboard("board", dev.url, "status"), "0 channels", "register 108",
                   "map=FILE")


def test_no_channel_count_register(device: Callable[..., Device]) -> None:
    dev = device(devices={1: board_like(ir_size=100)})
    one_line_error(dxboard("board", dev.url, "status"), "register 108", "exception 02",
                   "map=FILE")


def test_unit_not_served(device: Callable[..., Device]) -> None:
    dev = device(devices={7: board_like()})
    one_line_error(dxboard("board", dev.url, "status"), "unit 1", "exception 04", "?unit=")
    done = dxboard("board", dev.url + "?unit=7", "status")
    assert done.returncode == 0, done.stderr


def test_read_back_that_disagrees_says_what_disagrees(device: Callable[..., Device],
                                                      tmp_path: Path) -> None:
    dev = device(devices={1: board_like()})
    # the default map reads the switch back from discrete inputs, which this device never
    # changes: the switch is commanded on and reads back off
    done = dxboard("board", dev.url, "on", "1")
    one_line_error(done, "channel 1", "reads back off")
    # a map without read-back inputs but with state registers that never follow: the switch
    # reads back on, the channel's state stays off -- say exactly that
    m = tmp_path / "m.json"
    m.write_text(json.dumps({"channel_count": 108, "switch_coils": 0, "state_registers": 16}))
    done = dxboard("board", f"{dev.url}?map={m}", "on", "2")
    one_line_error(done, "channel 2", "reads back on", "state off")
    assert "reads back on (state" not in done.stderr
