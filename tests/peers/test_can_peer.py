"""The board's CAN front end against cantools (with protocol/dxboard.dbc) and python-can,
on both runtimes: nothing of ``protocol/`` is used to build or read a frame here.

The DBC says what the HMAC covers: the nonce as the eight bytes Nonce0..Nonce7 in bus order
(taken as one integer and written big-endian, it gets 201), then DXB_Cmd's data as sent.
``CurrentMa`` decodes in mA. A short DXB_Cmd is answered with 105, an unknown Op with 303.
"""

from __future__ import annotations

import hashlib
import hmac
import itertools
import json
import random
import time
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import can
import cantools
import pytest

from tests.emulator.wire import KEY, Emulate
from tests.ports import reserved_udp_port

DBC = Path(__file__).resolve().parents[2] / "protocol" / "dxboard.dbc"


class Peer:
    """A CAN tool on the board's bus: cantools decodes and encodes, python-can carries."""

    def __init__(self, group: str) -> None:
        self.db = cantools.database.load_file(str(DBC))
        self.bus = can.Bus(interface="udp_multicast", channel=group,
                           receive_own_messages=False)
        self.counter = itertools.count(int(time.time()))  # rises across the tests
        self.seen: dict[str, dict[str, Any]] = {}
        self.raw: dict[str, bytes] = {}

    def listen(self, until: Any, timeout: float = 10.0) -> dict[str, Any] | None:
        end = time.monotonic() + timeout
        while time.monotonic() < end:
            msg = self.bus.recv(0.2)
            if msg is None or msg.is_error_frame:
                continue
            try:
                m = self.db.get_message_by_frame_id(msg.arbitration_id)
                decoded = m.decode(msg.data, decode_choices=False)
            except (KeyError, cantools.database.DecodeError):
                continue  # not a frame of the DBC (or a command of ours echoed)
            self.seen[m.name] = decoded
            self.raw[m.name] = bytes(msg.data)
            if until(m.name, decoded):
                return decoded
        return None

    def nonce(self) -> bytes:
        self.listen(lambda name, _: name == "DXB_Nonce")
        sig = self.seen["DXB_Nonce"]
        return bytes(int(sig[f"Nonce{i}"]) for i in range(8))

    def send(self, name: str, values: dict[str, int] | None = None,
             data: bytes | None = None) -> None:
        m = self.db.get_message_by_name(name)
        payload = data if data is not None else m.encode(values or {})
        self.bus.send(can.Message(arbitration_id=m.frame_id, data=payload,
                                  is_extended_id=False))

    def command(self, op: int, channel: int, nonce: bytes | None = None,
                short: bool = False) -> dict[str, Any]:
        nonce = self.nonce() if nonce is None else nonce
        cmd = self.db.get_message_by_name("DXB_Cmd").encode(
            {"Op": op, "Channel": channel, "Force": 0, "OffTime100ms": 0,
             "Counter": next(self.counter)}, strict=op in (1, 2, 3, 4))
        if short:
            self.send("DXB_Cmd", data=cmd[:4])
        else:
            tag = hmac.new(KEY, nonce + cmd, hashlib.sha256).digest()[:16]
            self.send("DXB_Cmd", data=cmd)
            self.send("DXB_CmdTagA", {f"TagA{i}": tag[i] for i in range(8)})
            self.send("DXB_CmdTagB", {f"TagB{i}": tag[8 + i] for i in range(8)})
        got = self.listen(lambda name, sig: name == "DXB_CmdResult" and sig["Op"] == op
                          and sig["Channel"] == channel)
        assert got is not None, "no DXB_CmdResult"
        return got

    def channel(self, k: int) -> dict[str, Any]:
        self.seen.pop(f"DXB_Channel_{k}", None)
        got = self.listen(lambda name, _: name == f"DXB_Channel_{k}")
        assert got is not None
        return got

    def close(self) -> None:
        self.bus.shutdown()


@pytest.fixture(scope="module", params=["cpython", "micropython"])
def peer(request: pytest.FixtureRequest) -> Iterator[Peer]:
    # Linux hands a multicast datagram to every socket bound to its port, whatever group it
    # joined: a port of its own (python-can takes it from $CAN_CONFIG, here and in the
    # emulator, which inherits the environment) keeps a second copy of the suite off this bus
    group = f"239.74.{random.randrange(1, 250)}.{random.randrange(1, 250)}"
    with reserved_udp_port() as port, pytest.MonkeyPatch.context() as mp:
        mp.setenv("CAN_CONFIG", json.dumps({"port": port}))
        with Emulate("--runtime", request.param, "--can", f"udp_multicast:{group}"):
            p = Peer(group)
            try:
                yield p
            finally:
                p.close()


def test_broadcasts_decode_as_the_dbc_says(peer: Peer) -> None:
    got = peer.listen(lambda name, sig: name == "DXB_Channel_2" and sig["State"] == 2)
    assert got is not None, "the pc never reported on"  # the pc powers up by itself
    signal = peer.db.get_message_by_name("DXB_Channel_2").get_signal_by_name("CurrentMa")
    assert signal.unit == "mA" and signal.scale == 1
    assert 1000 <= got["CurrentMa"] <= 3500  # the pc draws about 2 A: in mA, as named
    assert peer.listen(lambda name, _: name == "DXB_Status") is not None
    assert 20 < peer.seen["DXB_Status"]["InputVoltage"] < 25
    nonce = peer.nonce()
    assert nonce == peer.raw["DXB_Nonce"]  # the signals are the bytes, in bus order


def test_command_authenticated_over_the_nonce_bytes(peer: Peer) -> None:
    res = peer.command(1, 6)  # on
    assert (res["Error"], res["Physical"]) == (0, 1), res
    assert peer.channel(6)["Commanded"] == 1
    res = peer.command(2, 6)  # off
    assert (res["Error"], res["Physical"]) == (0, 0), res


def test_nonce_read_as_one_integer_and_written_big_endian_is_refused(peer: Peer) -> None:
    nonce = peer.nonce()
    as_int = int.from_bytes(nonce, "little")  # how a 64-bit Intel signal would read it
    res = peer.command(1, 7, nonce=as_int.to_bytes(8, "big"))
    assert res["Error"] == 201
    assert peer.channel(7)["Commanded"] == 0  # nothing changed


def test_short_command_and_unknown_op_are_answered(peer: Peer) -> None:
    assert peer.command(1, 4, short=True)["Error"] == 105
    assert peer.command(9, 4)["Error"] == 303
    assert peer.channel(4)["Commanded"] == 0
