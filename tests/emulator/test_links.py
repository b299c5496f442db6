"""Serial (pty), CAN (python-can virtual bus) and the link-fault proxy of the emulated board."""

from __future__ import annotations

import asyncio
import json
import struct
import time
import uuid
from pathlib import Path

import can
import cantools
import serial

from emulator import model
from emulator.control import Background
from emulator.frontends import FrontEnds
from emulator.sim import Emulator
from host.launch.control import request as control
from protocol.can import OP_ON, command_frame, command_tag
from protocol.connection import HOST, Connection
from protocol.messages import GetState, Hello, HelloRequest, State, Switch, Switched
from tests.emulator.conftest import TEDUSAR
from tests.emulator.wire import KEY, Emulate, Wire

DBC = Path(__file__).resolve().parents[2] / "protocol" / "dxboard.dbc"


def test_serial_pty() -> None:
    with Emulate("--serial") as emu:
        path = emu.urls["serial"].removeprefix("serial://")
        port = serial.Serial(path, 115200, timeout=0.2)
        conn = Connection(HOST, KEY)

        def until(pred: object, seconds: float = 30.0) -> object:
            end = time.monotonic() + seconds
            while time.monotonic() < end:
                conn.receive_data(port.read(4096))
                for ev in conn.events():
                    if pred(ev):  # type: ignore[operator]
                        return ev
            raise AssertionError("no reply on the serial line")

        port.write(b"line noise \xdb\x00")
        port.write(conn.send(HelloRequest(req_id=1)))
        assert isinstance(until(lambda e: isinstance(e, Hello)), Hello)
        port.write(conn.send(Switch(6, True, req_id=2)))
        sw = until(lambda e: getattr(e, "req_id", 0) == 2)
        assert isinstance(sw, Switched) and sw.physical
        port.write(conn.send(GetState(req_id=3)))
        st = until(lambda e: getattr(e, "req_id", 0) == 3)
        assert isinstance(st, State) and st.channels[6].commanded
        port.close()


def _emulator() -> Emulator:
    cfg = json.loads((TEDUSAR / "board.json").read_text())
    cfg["board"]["key"] = KEY.hex()
    return Emulator(model.load(TEDUSAR), board_config=cfg)


def test_can_virtual_bus() -> None:
    db = cantools.database.load_file(str(DBC))
    channel = "dxb-" + uuid.uuid4().hex
    emu = _emulator()
    fronts = FrontEnds(emu)
    with Background(emu) as bg:
        urls = bg.run(fronts.start(can="virtual:" + channel))
        assert urls["can"] == f"can://virtual/{channel}"
        bus = can.Bus(interface="virtual", channel=channel)
        try:
            seen: dict[str, dict[str, object]] = {}
            nonce = b""
            end = time.monotonic() + 30  # a deadline, not a duration
            while time.monotonic() < end and not (
                    nonce and seen.get("DXB_Channel_2", {}).get("State") == "on"):
                msg = bus.recv(0.5)
                if msg is None:
                    continue
                m = db.get_message_by_frame_id(msg.arbitration_id)
                seen[m.name] = m.decode(msg.data)
                if m.name == "DXB_Nonce":
                    nonce = bytes(msg.data)
            assert seen["DXB_Channel_2"]["State"] == "on"  # the pc, on after power-up
            assert float(seen["DXB_Status"]["InputVoltage"]) > 20  # type: ignore[arg-type]
            cmd = command_frame(OP_ON, 6, counter=1)
            tag = command_tag(KEY, nonce, cmd)
            for can_id, data in ((0x180, cmd), (0x181, tag[:8]), (0x182, tag[8:])):
                bus.send(can.Message(arbitration_id=can_id, data=data, is_extended_id=False))
            result = None
            end = time.monotonic() + 30
            while time.monotonic() < end and result is None:
                msg = bus.recv(0.5)
                if msg is not None and msg.arbitration_id == 0x188:
                    result = db.decode_message(0x188, msg.data)
            assert result is not None
            assert result["Error"] == 0 and result["Channel"] == 6 and result["Physical"] == 1
            assert bg.call(lambda: emu.board.channels[6].commanded)
            replay = [(0x180, cmd), (0x181, tag[:8]), (0x182, tag[8:])]
            for can_id, data in replay:
                bus.send(can.Message(arbitration_id=can_id, data=data, is_extended_id=False))
            end = time.monotonic() + 30
            result = None
            while time.monotonic() < end and result is None:
                msg = bus.recv(0.5)
                if msg is not None and msg.arbitration_id == 0x188:
                    result = db.decode_message(0x188, msg.data)
            assert result is not None and result["Error"] == 202  # E_REPLAYED
        finally:
            bus.shutdown()
            bg.run(fronts.stop())


def test_dbc_round_trips() -> None:
    db = cantools.database.load_file(str(DBC))
    names = {m.name for m in db.messages}
    assert {"DXB_Status", "DXB_Currents_0", "DXB_Channel_0", "DXB_Nonce", "DXB_Cmd",
            "DXB_CmdTagA", "DXB_CmdTagB", "DXB_CmdResult"} <= names
    for m in db.messages:
        values = {}
        for sig in m.signals:
            if sig.choices:
                values[sig.name] = min(sig.choices)
            else:
                values[sig.name] = sig.maximum if sig.maximum is not None else 1
        data = m.encode(values, scaling=True)
        assert len(data) == m.length == 8
        back = m.decode(data, decode_choices=False)
        for k, v in values.items():
            assert abs(float(back[k]) - float(v)) < 1e-6 * max(1.0, abs(float(v))), (m.name, k)
    # the firmware's own encoders agree with the DBC
    from protocol.can import channel_frame, result_frame, status_frame

    ch = db.get_message_by_name("DXB_Channel_0").decode(
        channel_frame((True, False, 3, -1234, 0x21, 0, 7, 2)), decode_choices=False)
    assert (ch["State"], ch["Commanded"], ch["Physical"], ch["LiveFaults"], ch["Trips"],
            ch["Retries"]) == (3, 1, 0, 0x21, 7, 2)
    assert ch["CurrentMa"] == -1234  # decodes in mA, as its name says
    st = db.get_message_by_name("DXB_Status").decode(status_frame((23456, 0, 5000, 2, 1, 9)))
    assert (st["UptimeS"], st["BoardFlags"], st["ResetCause"], st["ConfigStatus"]) == (5, 9, 2, 1)
    assert abs(st["InputVoltage"] - 23.456) < 1e-9
    res = db.get_message_by_name("DXB_CmdResult").decode(result_frame(3, 4, 301, 4, True),
                                                         decode_choices=False)
    assert (res["Op"], res["Channel"], res["Error"], res["State"], res["Physical"]) == \
        (3, 4, 301, 4, 1)
    cmd = db.get_message_by_name("DXB_Cmd").decode(command_frame(3, 4, True, 20, 99),
                                                   decode_choices=False)
    assert (cmd["Op"], cmd["Channel"], cmd["Force"], cmd["OffTime100ms"], cmd["Counter"]) == \
        (3, 4, 1, 20, 99)
    assert struct.calcsize("<BBBBI") == 8


async def _until_closed(reader: asyncio.StreamReader) -> None:
    try:
        while await asyncio.wait_for(reader.read(65536), 5):
            pass
    except ConnectionResetError:
        pass


async def test_link_faults_at_the_proxy() -> None:
    with Emulate() as emu:
        url = emu.urls["control"]
        w = await Wire.open(emu.address())
        rep = await asyncio.to_thread(control, url, {"op": "inject", "channel": "board",
                                                     "fault": "link_delay",
                                                     "params": {"ms": 300}})
        assert rep["ok"], rep
        t0 = time.monotonic()
        assert isinstance(await w.request(GetState()), State)
        assert time.monotonic() - t0 >= 0.25  # delayed (a lower bound: the fault's effect)
        await asyncio.to_thread(control, url, {"op": "clear"})
        rep = await asyncio.to_thread(control, url, {"op": "inject", "channel": "board",
                                                     "fault": "link_disconnect", "params": {}})
        assert rep["ok"], rep
        await _until_closed(w.reader)  # the open connection is dropped
        r2, w2 = await asyncio.open_connection(*emu.address())
        await _until_closed(r2)  # and new ones are refused while the fault lasts
        w2.close()
        await asyncio.to_thread(control, url, {"op": "clear"})
        w3 = await Wire.open(emu.address())  # back after the fault is cleared
        assert isinstance(await w3.request(GetState()), State)
        await w3.close()
