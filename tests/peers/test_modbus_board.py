"""Our board's Modbus TCP server against pymodbus's own client, on both runtimes.

The write allow-list sees the client's address (not the emulator's link proxy's): a client
from 127.0.0.2 is refused when only 127.0.0.1 may write, and the one from 127.0.0.1 is
served; under ``--runtime micropython`` writes can be enabled at all (the firmware read
MicroPython's raw sockaddr before). FC15 is all or nothing on the wire too.
"""

from __future__ import annotations

from collections.abc import Iterator

import pytest
from pymodbus.client import AsyncModbusTcpClient

from host.board import BoardClient
from tests.emulator.wire import KEY, RUNTIMES, Emulate


@pytest.fixture(scope="module", params=list(RUNTIMES))
def board(request: pytest.FixtureRequest) -> Iterator[Emulate]:
    with Emulate(*RUNTIMES[request.param], "--modbus", "127.0.0.1:0") as emu:
        yield emu


async def modbus_from(board: Emulate, source: str) -> AsyncModbusTcpClient:
    host, port = board.address("modbus")
    client = AsyncModbusTcpClient(host, port=port, timeout=30, retries=0,
                                  source_address=(source, 0))
    assert await client.connect()
    return client


async def test_allow_list_checks_the_client_not_the_proxy(board: Emulate) -> None:
    async with BoardClient(board.urls["board"], KEY) as native:
        await native.configurator.set_board_config(modbus_write=True, modbus_allow=["127.0.0.1"])
        try:
            other = await modbus_from(board, "127.0.0.2")
            try:
                rw = await other.write_coil(6, True)
                assert rw.isError() and rw.exception_code == 1
            finally:
                other.close()
            assert not (await native.state()).channels[6].commanded
            local = await modbus_from(board, "127.0.0.1")
            try:
                rw = await local.write_coil(6, True)
                assert not rw.isError(), rw
                assert (await native.state()).channels[6].commanded
                # FC15 over channels 0..9 all off: the protected pc refuses -> nothing moves
                rw = await local.write_coils(0, [False] * 10)
                assert rw.isError() and rw.exception_code == 4
                assert (await native.state()).channels[6].commanded
                rw = await local.write_coil(6, False)
                assert not rw.isError()
            finally:
                local.close()
        finally:
            await native.configurator.set_board_config(modbus_write=False, modbus_allow=[])
