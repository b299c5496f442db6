"""The original TEDUSAR host driver (``tug_host_peer``: Controller.cpp, Message.cpp and main.cpp
byte for byte) against our board's tug front end, ``dxboard emulate --tug H:P --tug-switch``,
with the firmware under CPython and under the real MicroPython interpreter, and with the
shipped ``boot.py`` and ``main.py`` of each board revision (``--board-rev``: booted unmodified,
its configuration flashed with ``tug_port`` and ``tug_switch``).

It must get what the original board gave it: the specifications on connect, measurements once
a second although it asks for 200 Hz, a one-byte ACK it reads as ``ErrorCode= 0``, an answer
to its REQUEST (length 0 and a stray byte, 0x02 here, the worst case), status bytes 0 and 1
only (its hardware observer reads ``status == 1`` as on), and nothing switched by its
``shut_down`` action, which sends the eighth character of a device name as the channel.
"""

from __future__ import annotations

import asyncio
import time
from collections.abc import Iterator

import pytest

from host.board import BoardClient
from tests.host.emulate import KEY_HEX, Emulate
from tests.host.tug_host_peer import OriginalHost

KEY = bytes.fromhex(KEY_HEX)
TUG_OPTIONS = ("--tug", "127.0.0.1:0", "--tug-switch")
RATED_A = [1.5, 1.0, 5.0, 1.0, 1.0, 1.0, 0.5, 10.0, 1.0, 1.0]  # models/tedusar/board.json


RUNTIMES = {"cpython": ("--runtime", "cpython"), "micropython": ("--runtime", "micropython"),
            **{rev: ("--runtime", "micropython", "--board-rev", rev)
               for rev in ("rev-a", "rev-b", "rev-c")}}


@pytest.fixture(scope="module", params=list(RUNTIMES))
def emu(request: pytest.FixtureRequest) -> Iterator[Emulate]:
    e = Emulate(*TUG_OPTIONS, *RUNTIMES[request.param])
    yield e
    e.stop()


@pytest.fixture
def host(emu: Emulate) -> Iterator[OriginalHost]:
    hostname, _, port = emu.urls["tug"].removeprefix("tug://").rpartition(":")
    h = OriginalHost(hostname, int(port))
    yield h
    h.close()


def native_state(emu: Emulate, ch: int) -> tuple[bool, bool]:
    async def get() -> tuple[bool, bool]:
        async with BoardClient(emu.urls["board"], KEY) as c:
            st = await c.state()
            return st.channels[ch].commanded, st.channels[ch].physical

    return asyncio.run(get())


def test_specifications_on_connect(host: OriginalHost) -> None:
    assert host.wait_until(lambda: host.specifications)
    specs = host.specifications[0]
    assert [round(a, 3) for a, _v in specs] == RATED_A
    assert all(20.0 < v < 30.0 for _a, v in specs), specs  # the board's input voltage
    first = host.frames[0]
    assert first[0] == 0 and first[1] == 1 + 8 * 10  # the first frame, before anything asked


def test_broadcast_once_a_second_whatever_rate_is_asked(host: OriginalHost) -> None:
    start = time.monotonic()
    assert host.wait_until(lambda: len(host.measurments) >= 3, timeout=30)
    elapsed = time.monotonic() - start
    with host.lock:
        got = list(host.measurments)
        published = [p for p in host.published if p.channel]
    # 200 Hz was asked; the original board sends once a second: never more than that
    assert len(got) <= elapsed + 2
    assert all(len(m) == 10 for m in got)
    assert len(published) == len(got)
    assert {ch.status for p in published for ch in p.channel} <= {0, 1}
    pc = published[-1].channel[2]  # the first may precede the power-up of a fresh board
    assert pc.dev_connected == "pc" and pc.status == 1 and pc.current > 0


def test_power_up_is_acknowledged_as_success(emu: Emulate, host: OriginalHost) -> None:
    assert host.wait_until(lambda: host.specifications)
    assert host.power_up("router") == 5
    assert host.wait_until(lambda: host.ecodes)
    assert host.printed == [" ErrorCode= 0"]
    assert host.wait_until(
        lambda: any(p.channel and p.channel[5].status == 1 for p in host.published))
    assert native_state(emu, 5) == (True, True)
    host.call_message_channel_on_off(5, 0)
    assert host.wait_until(lambda: len(host.ecodes) == 2)
    assert host.ecodes == [0, 0]
    assert native_state(emu, 5)[0] is False


def test_request_with_a_stray_byte_is_answered(emu: Emulate, host: OriginalHost) -> None:
    assert host.wait_until(lambda: host.specifications)
    before = len(host.measurments)
    host.call_message_request(stray=0x02)
    assert host.wait_until(lambda: host.ecodes and len(host.measurments) > before)
    # the stray 0x02 must not swallow what follows
    host.power_up("kinect")
    assert host.wait_until(lambda: len(host.ecodes) == 2)
    assert host.ecodes == [0, 0]
    assert host.wait_until(  # the switch follows at the board's next protection step
        lambda: any(p.channel and p.channel[4].status == 1 for p in host.published))
    assert native_state(emu, 4) == (True, True)
    host.call_message_channel_on_off(4, 0)
    assert host.wait_until(lambda: len(host.ecodes) == 3)


def test_refusals_change_nothing(emu: Emulate, host: OriginalHost) -> None:
    assert host.wait_until(lambda: host.specifications)
    # the protected PC on, and its switch's output up (some 50 ms of the board's boot: a board
    # just booted for this test had it commanded, not yet physical)
    assert host.wait_until(lambda: native_state(emu, 2) == (True, True))
    assert host.shut_down("thermal_camera") == ord("_")  # main.cpp 65: no such channel
    host.call_message_channel_on_off(2, 0)  # the protected PC
    assert host.wait_until(lambda: len(host.ecodes) == 2)
    assert all(code != 0 for code in host.ecodes)
    assert native_state(emu, 2) == (True, True)
