"""A board that stalls long enough for the link to be lost is not said to have rebooted when its
HELLO carries the same boot id: over the native protocol, and over Modbus, whose boot id
registers (110-111) carry the board's own.

The emulator lets its simulated clock slip when its process cannot keep up for more than
``emulator.control.MAX_LAG_MS`` (a loaded machine, or here a stopped process), so the board's
uptime falls behind the host's clock. The host's uptime rule (``host.board.link``: an uptime
lower than the one seen before plus the time in between) is for links whose HELLO has no boot id
of the board's own (Modbus, the original TEDUSAR format); over the native protocol the boot id
is random at every boot (PROTOCOL.md section 2) and the same one is the same boot. Before, a
stall of a few seconds over TCP was reported as a reboot: the daemon reset its repair attempts
and forgot what its hardware observer knew (found while stopping an emulator in a test).
"""

from __future__ import annotations

import asyncio
import time

import psutil
import pytest

from host.board import BoardClient
from host.board.types import LinkDown, LinkUp, Rebooted, StreamItem
from tests.emulator.wire import KEY, Emulate
from tests.wait import wait_until_async

STALL_S = 6.0  # past the link's silence limit and the emulator's catch-up (2 s)


@pytest.mark.parametrize("link", ["board", "modbus"])
async def test_a_stalled_board_with_the_same_boot_id_did_not_reboot(link: str) -> None:
    with Emulate("--modbus", "127.0.0.1:0") as emu:
        async with BoardClient(emu.urls[link], KEY if link == "board" else None,
                               timeout_s=30.0) as client:
            boot = client.info.boot_id if client.info else None
            stream = client.subscribe(20).__aiter__()
            seen: list[StreamItem] = []

            async def take() -> None:
                seen.append(await stream.__anext__())

            await wait_until_async(lambda: len(seen) >= 3, 60, "readings", interval=0,
                                   each=take)
            board = psutil.Process(emu.child.pid)
            board.suspend()  # the board's whole process stalls; its clock slips
            try:
                stalled = time.monotonic()
                while time.monotonic() - stalled < STALL_S:  # the link is lost meanwhile
                    await asyncio.sleep(0.1)
            finally:
                board.resume()
            mark = len(seen)
            await wait_until_async(lambda: any(isinstance(i, LinkUp) for i in seen[mark:]),
                                   120, "the link back", interval=0, each=take,
                                   show=lambda: seen[-5:])
            assert any(isinstance(i, LinkDown) for i in seen), seen[-10:]
            assert not [i for i in seen if isinstance(i, Rebooted)], seen[-10:]
            assert client.info is not None and client.info.boot_id == boot
