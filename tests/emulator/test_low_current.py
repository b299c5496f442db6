"""Rev C end to end: a small load is *low, not measured*, and the host diagnoses nothing.

``dxboard emulate models/tedusar --runtime micropython --board-rev rev-c`` runs the shipped
``main.py`` on the smart-switch models: the thermal camera (channel 6, 80 mA at the battery,
its band 0.03-0.3 A in ``system.yaml``) draws less than rev C's current sense can measure
(100 mA, ``firmware/boards/rev_c.py``). The board reads 0 for it and says ``low`` (PROTOCOL.md
section 10): a peer written from PROTOCOL.md alone decodes the flag and the range EVENT; the
host's own client decodes it as ``low``, its hardware observer leaves the camera's current
unknown (never ``under`` its band, never an open load) while it judges the measured devices,
and the diagnosis of what it observed names no component. Over Modbus, which carries the live
flags but no events, the host's transport makes the same range EVENT from the flag.
"""

from __future__ import annotations

import struct
import time
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest

from host.board import BoardClient
from host.board.types import BoardEvent, BoardState, Reading
from host.diagnosis.diagnoser import Diagnoser
from host.diagnosis.files import load_encoded, read_observations
from host.diagnosis.model import load_system
from host.observers import HardwareObserver
from host.observers.config import load_observers
from tests.emulator.wire import KEY, RUNTIMES, TEDUSAR, Emulate
from tests.peers import spec_client as sc
from tests.peers.test_native_peer import Tcp
from tests.wait import wait_until_async

CAMERA = 6
SWITCHED = {"laser_alignment": 1, "hokuyo": 3, "thermal_camera": CAMERA, "jaguar": 7}
# PROTOCOL.md section 10, read by a peer that shares no code with ours
LOW = 0x0400
RANGE = 7


@pytest.fixture(scope="module")
def board() -> Iterator[Emulate]:
    with Emulate(*RUNTIMES["rev-c"], "--modbus", "127.0.0.1:0") as emu:
        yield emu


def test_the_spec_peer_reads_low_not_measured(board: Emulate) -> None:
    link = Tcp(board.address())
    try:
        peer = sc.SpecPeer(link.send, link.recv, KEY)
        peer.greet(ask=False, timeout=60)
        assert peer.request(sc.SUBSCRIBE, bytes([20]), timeout=60).type == sc.ACK
        got = peer.signed(sc.SWITCH, bytes([CAMERA, 1, 0]), timeout=60)
        assert got.type == sc.SWITCHED, sc.parse_error(got.payload)

        def range_event(f: sc.Frame) -> bool:
            if f.type != sc.EVENT:
                return False
            _seq, _up, kind, ch, old, new, flags, value, _dropped = struct.unpack(
                ">IIBBBBHiH", f.payload)
            return kind == RANGE and ch == CAMERA and flags == LOW and old == new \
                and value == 0

        said_at = struct.unpack_from(">I", peer.wait(range_event, timeout=60).payload, 4)[0]
        cam = sc.parse_state(peer.request(sc.GET_STATE, timeout=60).payload)["channels"][CAMERA]
        # its current: 0, or a reading the flag does not wait for (50 measured in a row end it)
        assert cam["physical"] and cam["live_faults"] & LOW, cam
        assert not cam["sticky_faults"], cam  # not a fault, and never sticky
        # readings after the EVENT, until one reads the camera's 0: none has a live fault
        got: list[dict[str, Any]] = []
        end = time.monotonic() + 60
        while not got or got[-1]["currents_ma"][CAMERA] != 0:
            assert time.monotonic() < end, got[-20:]
            got += [m for m in peer.measurements(1, timeout=60) if m["uptime_ms"] >= said_at]
        assert all(m["on_mask"] >> CAMERA & 1 and not m["fault_mask"] >> CAMERA & 1
                   for m in got), got
    finally:
        link.sock.close()


async def test_the_host_leaves_it_unknown_and_diagnoses_nothing(board: Emulate,
                                                                tmp_path: Path) -> None:
    (configured,) = [o for o in load_observers(TEDUSAR, load_system(TEDUSAR)).observers
                     if isinstance(o, HardwareObserver)]
    # the devices as system.yaml wires them; a lenient link rule (a busy machine's gaps are
    # not what this test is about)
    hw = HardwareObserver(configured.devices, link_timeout=5.0, link_slack=5.0)
    seen: list[BoardEvent] = []
    async with BoardClient(board.urls["board"], KEY, timeout_s=30.0) as client:
        for ch in SWITCHED.values():
            await client.switch(ch, True)
        state = await client.state()
        hw.feed(state, time.monotonic())
        stream = client.subscribe(20).__aiter__()

        async def feed() -> None:
            item = await stream.__anext__()
            if isinstance(item, BoardEvent):
                seen.append(item)
            if isinstance(item, BoardEvent | BoardState | Reading):
                hw.feed(item, time.monotonic())

        def settled() -> bool:
            a = hw.asserted
            return hw.low == {"thermal_camera"} and all(
                a.get(f"on({d})") is True for d in SWITCHED) and all(
                a.get(f"in_band({d})") is True for d in SWITCHED if d != "thermal_camera")

        await wait_until_async(settled, timeout=120, what="the devices on, the camera low",
                               each=feed, interval=0, show=lambda: (hw.asserted, hw.low))
        cam = (await client.state()).channels[CAMERA]
        assert cam.to_dict()["live_faults"] == ["low"] and cam.state_name == "on", cam
    assert "in_band(thermal_camera)" not in hw.asserted
    assert "thermal_camera" not in hw.bands and not hw.doubted
    assert hw.asserted["tripped(thermal_camera)"] is False
    assert not [e for e in seen if e.channel == CAMERA and e.kind_name in ("trip", "fault",
                                                                           "warning")]
    # what the host observed, diagnosed: nothing is broken
    encoding = load_encoded(TEDUSAR)
    obs = tmp_path / "observed.txt"
    obs.write_text("".join(f"{'' if v else '~'}{atom}\n" for atom, v in hw.asserted.items()
                           if atom in encoding.theory.atoms()))
    with Diagnoser(encoding.theory, encoding=encoding) as diagnoser:
        for o in read_observations(obs, encoding.theory):
            diagnoser.observe(o)
        result = diagnoser.diagnose()
    assert result.bad_sets() == [frozenset()], result.bad_sets()


async def test_over_modbus_the_host_gets_the_same_range_event(board: Emulate) -> None:
    async with BoardClient(board.urls["board"], KEY, timeout_s=30.0) as native:
        await native.switch(CAMERA, True)
    async with BoardClient(board.urls["modbus"], timeout_s=30.0) as mb:
        stream = mb.subscribe(20).__aiter__()
        said: list[BoardEvent] = []
        readings: list[Reading] = []
        other: list[object] = []  # link notices, the other channels' events

        async def take() -> None:
            item = await stream.__anext__()
            if isinstance(item, BoardEvent) and item.channel == CAMERA:
                said.append(item)
            elif isinstance(item, Reading):
                if said:
                    readings.append(item)
            else:
                other.append(item)

        await wait_until_async(lambda: len(readings) >= 5, timeout=120, interval=0, each=take,
                               what="a range event and readings after it over Modbus",
                               show=lambda: (said, readings[-2:], other[-5:]))
        assert said[0].kind_name == "range" and said[0].faults == LOW, said
        assert all(r.on_mask >> CAMERA & 1 and not r.fault_mask >> CAMERA & 1
                   for r in readings), readings
        cam = (await mb.state()).channels[CAMERA]
        assert "low" in cam.to_dict()["live_faults"], cam
