"""A deep brown-out holds the microcontroller in reset: every connection drops and nothing is
served or executed until the board boots again (issue 12), on both runtimes."""

from __future__ import annotations

import asyncio
import struct
import time
from collections.abc import Iterator

import pytest

from host.commands.inject import request as control
from protocol.constants import RESET_BROWNOUT
from protocol.messages import GetState, Hello, State, Switch
from tests.emulator.wire import Emulate, Wire


@pytest.fixture(scope="module", params=["cpython", "micropython"])
def board(request: pytest.FixtureRequest) -> Iterator[Emulate]:
    with Emulate("--runtime", request.param, "--modbus", "127.0.0.1:0") as emu:
        yield emu


async def closed(reader: asyncio.StreamReader, timeout: float = 5.0) -> bool:
    """True when the peer closes the stream within ``timeout`` (data before is read away)."""
    loop = asyncio.get_running_loop()
    end = loop.time() + timeout
    try:
        while loop.time() < end:
            if not await asyncio.wait_for(reader.read(65536), end - loop.time()):
                return True
    except ConnectionError:
        return True
    except TimeoutError:
        pass
    return False


async def test_deep_brownout_drops_everything_and_executes_nothing(board: Emulate) -> None:
    w = await Wire.open(board.address())
    mr, mw = await asyncio.open_connection(*board.address("modbus"))
    mw.write(struct.pack(">HHHBBHH", 1, 0, 6, 1, 4, 100, 1))  # a good Modbus request
    await mw.drain()
    assert len(await asyncio.wait_for(mr.readexactly(11), 5)) == 11
    rep = await asyncio.to_thread(control, board.urls["control"],
                                  {"op": "inject", "channel": "board", "fault": "brownout",
                                   "params": {"volts": 3, "seconds": 3}})
    assert rep["ok"], rep
    t0 = time.monotonic()
    assert await closed(w.reader), "the native connection survived the reset"
    assert await closed(mr), "the Modbus connection survived the reset"
    # while held in reset: a new connection is dropped without a HELLO, and nothing runs
    if time.monotonic() - t0 < 2.0:
        r2, w2 = await asyncio.open_connection(*board.address())
        w2.write(b"\x00" * 8)
        assert await closed(r2, 2.0)
        assert not [x for x in (await _drain(r2)) if x]
    # after the brown-out, the board boots again and serves
    loop = asyncio.get_running_loop()
    end = loop.time() + 20
    while True:
        try:
            w3 = await Wire.open(board.address(), )
            break
        except (AssertionError, ConnectionError, TimeoutError):
            assert loop.time() < end, "the board did not come back"
            await asyncio.sleep(0.2)
    assert isinstance(w3.hello, Hello) and w3.hello.reset_cause == RESET_BROWNOUT
    st = await w3.request(GetState())
    assert isinstance(st, State) and not st.channels[6].commanded
    assert (await w3.request(Switch(6, False))) is not None
    await w3.close()
    await w.close()
    mw.close()


async def _drain(reader: asyncio.StreamReader) -> list[bytes]:
    try:
        return [await asyncio.wait_for(reader.read(65536), 0.1)]
    except (TimeoutError, ConnectionError):
        return []
