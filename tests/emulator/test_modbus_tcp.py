"""A pymodbus client reads the emulated board's Modbus TCP map: the native protocol agrees."""

from __future__ import annotations

import asyncio
import struct
from collections.abc import Iterator

import pytest
from pymodbus.client import AsyncModbusTcpClient

from protocol.constants import NOT_FAULTS, ST_ON
from protocol.messages import Ack, GetState, Measurement, State, Subscribe, Switch, Switched
from tests.emulator.wire import RUNTIMES, Emulate, Wire
from tests.wait import wait_until_async


@pytest.fixture(scope="module", params=list(RUNTIMES))
def board(request: pytest.FixtureRequest) -> Iterator[Emulate]:
    with Emulate(*RUNTIMES[request.param], "--modbus", "127.0.0.1:0") as emu:
        yield emu


def u32(hi: int, lo: int) -> int:
    return (hi << 16) | lo


async def test_modbus_matches_native(board: Emulate) -> None:
    w = await Wire.open(board.address())
    for ch in (0, 3, 6):
        assert isinstance(await w.request(Switch(ch, True)), Switched)

    async def all_on() -> bool:  # their inrush over
        st = await w.request(GetState())
        return isinstance(st, State) and all(st.channels[ch].state == ST_ON for ch in (0, 3, 6))

    await wait_until_async(all_on, what="channels 0, 3 and 6 on")
    assert isinstance(await w.request(Subscribe(100)), Ack)
    host, port = board.address("modbus")
    client = AsyncModbusTcpClient(host, port=port, timeout=30, retries=0)
    assert await client.connect()
    try:
        snaps = []
        for _ in range(3):
            rr = await client.read_input_registers(0, count=110, device_id=17)  # one snapshot
            assert not rr.isError(), rr
            snaps.append((rr.registers[:80], rr.registers[100:110]))
            await asyncio.sleep(0.05)
        coils = await client.read_coils(0, count=16)
        discrete = await client.read_discrete_inputs(0, count=32)
        assert not coils.isError() and not discrete.isError()
        st = await w.request(GetState())
        assert isinstance(st, State)
        # measurements pushed by the native protocol, by uptime: find each Modbus snapshot's
        # every push up to a tick after the last snapshot's (they come in order)
        meas: dict[int, Measurement] = {}
        last_up = u32(snaps[-1][1][3], snaps[-1][1][4])
        while not meas or max(meas) <= last_up:
            m = await w.next(lambda e: isinstance(e, Measurement))
            assert isinstance(m, Measurement)
            meas[m.uptime_ms] = m
        matched = 0
        for regs, board_regs in snaps:
            up = u32(board_regs[3], board_regs[4])
            if up not in meas:
                continue
            # the input registers of one read are one tick's snapshot, as is the measurement
            m = meas[up]
            assert regs[:10] == [max(0, min(65535, ma)) for ma in m.currents_ma]
            assert sum(regs[:10]) > 0
            matched += 1
        # at least the last snapshot's tick is still within the collected pushes
        assert matched >= 1, (sorted(meas)[:3], [s[1][3:5] for s in snaps])
        regs, board_regs = snaps[-1]
        for c in st.channels:
            k = c.channel
            assert regs[16 + k] == c.state
            assert regs[32 + k] == c.live_faults
            assert regs[48 + k] == c.sticky_faults
            assert regs[64 + k] == c.trips
            assert coils.bits[k] == c.commanded
            assert discrete.bits[k] == c.physical
            assert discrete.bits[16 + k] == bool(c.live_faults & ~NOT_FAULTS)  # low: no fault
        assert regs[10:16] == [0] * 6  # no channels 10..15
        assert board_regs[6] == st.reset_cause and board_regs[7] == st.config_status
        assert board_regs[8] == 10 and board_regs[9] == 1
        boot = await client.read_input_registers(110, count=2)  # the boot id, high word first
        assert not boot.isError() and w.hello is not None
        assert u32(boot.registers[0], boot.registers[1]) == w.hello.boot_id
        assert abs(board_regs[0] - st.input_mv) < 500
        # configuration: channel 3 (hokuyo, rated 1000 mA) and the board's tick
        hold = await client.read_holding_registers(1000 + 32 * 3, count=22)
        assert not hold.isError()
        assert u32(hold.registers[0], hold.registers[1]) == 1000
        hb = await client.read_holding_registers(900, count=10)
        assert u32(hb.registers[0], hb.registers[1]) == 20000 and hb.registers[6] == 10
        # writes: off by default (board.json has no modbus_write): exception 01, nothing changes
        rw = await client.write_coil(3, False)
        assert rw.isError() and rw.exception_code == 1
        rw = await client.write_register(1000 + 32 * 3 + 1, 2000)
        assert rw.isError() and rw.exception_code == 1
        bad = await client.read_input_registers(105, count=10)  # past 111, the last
        assert bad.isError() and bad.exception_code == 2
    finally:
        client.close()
    st = await w.request(GetState())
    assert isinstance(st, State) and st.channels[3].commanded and st.channels[3].physical
    for ch in (0, 3, 6):
        await w.request(Switch(ch, False))
    await w.close()


async def test_bad_mbap_closes_connection(board: Emulate) -> None:
    r, wr = await asyncio.open_connection(*board.address("modbus"))
    wr.write(struct.pack(">HHHBBHH", 1, 0, 6, 1, 4, 100, 1))  # a good request first
    await wr.drain()
    good = await asyncio.wait_for(r.readexactly(11), 30)
    assert good[7] == 4 and struct.unpack(">H", good[9:11])[0] > 0
    wr.write(struct.pack(">HHHBBHH", 2, 7, 6, 1, 4, 100, 1))  # protocol id 7
    await wr.drain()
    assert await asyncio.wait_for(r.read(100), 30) == b""
    wr.close()
