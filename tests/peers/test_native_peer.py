"""The native front ends (TCP and serial) against a host written from PROTOCOL.md alone.

``tests/peers/spec_client.py`` shares no code with ``protocol/``: if it can greet, read,
subscribe and switch, the specification and the board agree. The same peer also shows two
findings of issue 12: a serial line that a program left half a frame on is heard again after
250 ms of silence (also after reopening the port), and a new session (HELLO_REQUEST) starts
without a subscription and counts its measurements from 1.
"""

from __future__ import annotations

import re
import socket
import struct
import time
from collections.abc import Iterator
from pathlib import Path

import pytest
import serial

from tests.emulator.wire import KEY, RUNTIMES, Emulate
from tests.peers import spec_client as sc


@pytest.fixture(scope="module", params=list(RUNTIMES))
def board(request: pytest.FixtureRequest) -> Iterator[Emulate]:
    with Emulate(*RUNTIMES[request.param], "--serial") as emu:
        yield emu


class Tcp:
    def __init__(self, address: tuple[str, int]) -> None:
        self.sock = socket.create_connection(address, timeout=10)

    def send(self, data: bytes) -> None:
        self.sock.sendall(data)

    def recv(self, timeout: float) -> bytes:
        self.sock.settimeout(timeout)
        try:
            data = self.sock.recv(65536)
        except TimeoutError:
            return b""
        if not data:
            raise AssertionError("the board closed the connection")
        return data

    def close(self) -> None:
        self.sock.close()


class Serial:
    def __init__(self, path: str) -> None:
        self.port = serial.Serial(path, 115200, timeout=0.1)

    def send(self, data: bytes) -> None:
        self.port.write(data)

    def recv(self, timeout: float) -> bytes:
        self.port.timeout = timeout
        return bytes(self.port.read(max(1, self.port.in_waiting)))

    def close(self) -> None:
        self.port.close()


def open_peer(board: Emulate, how: str, key: bytes | None = KEY) -> tuple[sc.SpecPeer, object]:
    link: Tcp | Serial
    if how == "tcp":
        link = Tcp(board.address())
        peer = sc.SpecPeer(link.send, link.recv, key)
        peer.greet(ask=False)
    else:
        link = Serial(board.urls["serial"].removeprefix("serial://"))
        peer = sc.SpecPeer(link.send, link.recv, key)
        peer.greet(ask=True)
    return peer, link


@pytest.mark.parametrize("how", ["tcp", "serial"])
def test_spec_peer_reads_subscribes_and_switches(board: Emulate, how: str) -> None:
    peer, link = open_peer(board, how)
    try:
        hello = peer.hello
        assert hello is not None and hello["version"] == 1 and hello["channels"] == 10
        assert hello["board_id"] == "tedusar" and len(hello["nonce"]) == 16
        token, uptime = peer.ping(0xC0DE)
        assert token == 0xC0DE and uptime >= 0
        st = peer.state()
        assert [c["channel"] for c in st["channels"]] == list(range(10))
        assert peer.subscribe(50).type == sc.ACK
        seqs = [m["seq"] for m in peer.measurements(20)]
        assert seqs == list(range(seqs[0], seqs[0] + 20))
        assert peer.subscribe(0).type == sc.ACK
        got = peer.switch(6, True)
        assert got.type == sc.SWITCHED, sc.parse_error(got.payload)
        assert got.payload[0] == 6 and got.payload[1] == 1 and got.payload[2] == 1
        got = peer.switch(6, False)
        assert got.type == sc.SWITCHED and got.payload[2] == 0
    finally:
        link.close()  # type: ignore[attr-defined]


@pytest.mark.parametrize("how", ["tcp", "serial"])
def test_wrong_key_changes_nothing(board: Emulate, how: str) -> None:
    peer, link = open_peer(board, how, key=b"\x55" * 32)
    try:
        got = peer.switch(8, True)
        assert got.type == sc.ERROR and sc.parse_error(got.payload)["code"] == 201
        assert not peer.state()["channels"][8]["commanded"]
    finally:
        link.close()  # type: ignore[attr-defined]


@pytest.mark.parametrize("how", ["tcp", "serial"])
def test_new_session_has_no_subscription_and_counts_from_1(board: Emulate, how: str) -> None:
    peer, link = open_peer(board, how)
    try:
        assert peer.subscribe(100).type == sc.ACK
        assert peer.measurements(10)[-1]["seq"] >= 10
        rid = peer.next_id()
        link.send(sc.frame(sc.HELLO_REQUEST, rid, b""))  # type: ignore[attr-defined]
        frames: list[sc.Frame] = []
        end = time.monotonic() + 5
        while not any(f.type == sc.HELLO and f.req_id == rid for f in frames):
            assert time.monotonic() < end, frames
            frames += peer.decoder.feed(link.recv(0.2))  # type: ignore[attr-defined]
        # after the new HELLO: nothing pushed until SUBSCRIBE, and then seq 1 first
        peer.backlog = frames[[f.type for f in frames].index(sc.HELLO) + 1:]
        state = peer.request(sc.GET_STATE)
        assert state.type == sc.STATE
        assert not [f for f in peer.backlog if f.type == sc.MEASUREMENT]
        assert peer.subscribe(100).type == sc.ACK
        assert peer.measurements(1)[0]["seq"] == 1
        peer.subscribe(0)
    finally:
        link.close()  # type: ignore[attr-defined]


def test_serial_partial_frame_is_dropped_after_silence(board: Emulate) -> None:
    """A program writes 7 bytes of a frame and exits; the next program opens the port and is
    answered at once (the board dropped the stale partial frame after 250 ms of silence)."""
    path = board.urls["serial"].removeprefix("serial://")
    first = serial.Serial(path, 115200, timeout=0.1)
    first.write(sc.frame(sc.PING, 1, struct.pack(">I", 1) + bytes(227))[:7])
    first.flush()
    first.close()
    time.sleep(0.4)  # the silence that ends the frame (the stimulus, not a wait for a result)
    link = Serial(path)
    try:
        peer = sc.SpecPeer(link.send, link.recv, KEY)
        hello = peer.greet(ask=True, timeout=30.0)
        assert hello["board_id"] == "tedusar"
        assert peer.ping(7)[0] == 7
    finally:
        link.close()


def test_the_spec_example_batch_decodes_as_the_text_says() -> None:
    """PROTOCOL.md §7's MEASUREMENT_BATCH example, read by the peer written from §4.2."""
    text = (Path(__file__).resolve().parents[2] / "protocol" / "PROTOCOL.md").read_text()
    after = text[text.index("MEASUREMENT_BATCH of 2 readings"):]
    hexline = re.search(r"```\n([0-9a-f]+)\n```", after)
    assert hexline is not None
    frames = sc.Decoder().feed(bytes.fromhex(hexline.group(1)))
    assert [f.type for f in frames] == [sc.MEASUREMENT_BATCH]
    got = sc.parse_batch(frames[0].payload)
    assert [(r["seq"], r["uptime_ms"], r["input_mv"]) for r in got] == [
        (17, 61260, 24090), (18, 61270, 24085)]
    assert got[0]["currents_ma"] == [1510, -3, 0, 702, 0, 0, 0, 4980, 0, 0]
    for bad in (b"\x00\x01", b"\x03\x01" + bytes(36), b"\x02\x01" + bytes(35),
                frames[0].payload + b"\x00"):
        with pytest.raises(ValueError):
            sc.parse_batch(bad)


@pytest.mark.parametrize("how", ["tcp", "serial"])
def test_spec_peer_reads_batches_and_answers_come_after_them(board: Emulate, how: str) -> None:
    peer, link = open_peer(board, how)
    try:
        assert peer.hello is not None and peer.hello["capabilities"] & sc.CAP_BATCH
        for k in (0, 11):  # §4.2: per_frame 1-10
            got = peer.subscribe(100, k)
            assert got.type == sc.ERROR and sc.parse_error(got.payload)["code"] == 303
        assert peer.subscribe(100, 4).type == sc.ACK
        readings = peer.measurements(60)
        seqs = [r["seq"] for r in readings]
        assert seqs == list(range(seqs[0], seqs[0] + len(seqs)))
        assert sc.MEASUREMENT not in [f.type for f in peer.backlog]  # batched
        # PINGs: every reading sampled before a PONG arrives before it, none is lost or
        # reordered, and (10 a frame: readings are held 90 % of the time) a PONG finds some
        assert peer.subscribe(100, 10).type == sc.ACK
        frames = list(peer.backlog)
        pongs: list[int] = []  # indices into frames
        for token in range(5):
            rid = peer.next_id()
            link.send(sc.frame(sc.PING, rid, struct.pack(">I", token)))  # type: ignore[attr-defined]
            end = time.monotonic() + 10
            while not any(f.type == sc.PONG and f.req_id == rid for f in frames):
                assert time.monotonic() < end, frames
                frames += peer.decoder.feed(link.recv(0.2))  # type: ignore[attr-defined]
            pongs.append(next(i for i, f in enumerate(frames) if f.req_id == rid))
            time.sleep(0.037)  # a PING at another phase of the batch (the stimulus)
        frames += peer.decoder.feed(link.recv(0.3))  # type: ignore[attr-defined]
        batches = [(i, sc.parse_batch(f.payload)) for i, f in enumerate(frames)
                   if f.type == sc.MEASUREMENT_BATCH]
        assert all(len(b) <= 10 for _, b in batches)
        seqs = [r["seq"] for _, b in batches for r in b]
        assert seqs == list(range(seqs[0], seqs[0] + len(seqs)))
        for at in pongs:
            up = struct.unpack(">II", frames[at].payload)[1]
            assert all(r["uptime_ms"] <= up for i, b in batches if i < at for r in b)
            assert all(r["uptime_ms"] >= up for i, b in batches if i > at for r in b)
        assert any(frames[at - 1].type == sc.MEASUREMENT_BATCH for at in pongs)
        peer.backlog = []
        assert peer.subscribe(0).type == sc.ACK
    finally:
        link.close()  # type: ignore[attr-defined]
