"""A HAL whose electronics live elsewhere: the firmware in ``micropython``, fed by the emulator.

``micropython -m firmware.hal.remote HOST PORT`` connects twice to the emulator
(``emulator/mpy.py``), which keeps the simulated electronics and the clock; this process runs
the real firmware (``App``) and its front ends (``firmware.net``, ``.modbus``, ``.tug``) on
MicroPython's asyncio. Two links, JSON lines (``\\n``-terminated), lock-step:

- link A, emulator -> firmware, one reply per request, read by an asyncio task here:
  ``{"op": "boot", "cause": C, "n": N, "seed": S, "tcp": P, "modbus": P|null, "tug": P|null,
  "tug_switch": B, "serial": P|null, "can": {"node": N, "rate": HZ}|null,
  "factory": CONFIG|null}`` builds a new ``App`` (with that factory configuration) on a new
  ``RemoteHal`` (the first boot also starts the servers on 127.0.0.1: the native protocol,
  Modbus behind the emulator's proxy, the original TEDUSAR format, and the serial line, which
  the emulator relays to its pty byte for byte) and, with ``can``, a new ``CanNode``;
  ``{"op": "step", "t": ms, "ma": [..], "sw": [..], "mv": mv}`` sets this step's clock and
  readings, runs ``App.step``, ``Net.pump`` and the CAN node's ``poll``, answers ``{"due",
  "feeds", "reboot", "can": [[id, hex], ..]}``; ``{"op": "can", "id": ID, "data": hex}`` hands
  a frame from the bus to the CAN node and answers ``{"frames": [[id, hex], ..]}`` to send;
  ``{"op": "halt"}`` closes every connection and serves nothing until the next boot (the
  board held in reset);
  ``{"op": "call", "m": NAME, "a": [..]}`` calls a ``Board`` method (the emulator's status,
  scenario commands) and answers ``{"r": result}``; ``{"op": "mem"}`` collects garbage and
  answers ``{"alloc": B, "free": B}``: the heap the running firmware holds beyond what was
  allocated once its modules were imported (benchmarks).
- link B, firmware -> emulator, a blocking request whenever the firmware must act at once:
  ``["set_switch", ch, on]`` -> the switch read-backs after it; storage ``["read", name]``
  (hex or null), ``["write", name, hex]``, ``["rename", a, b]``, ``["remove", name]``.

Between steps the readings stay those of the last step, as a sampled ADC's would.
"""

import asyncio
import binascii
import gc
import json
import random
import socket
import sys

from firmware import modbus, tug
from firmware.app import App
from firmware.can import CanNode
from firmware.net import Net
from firmware.session import FIRMWARE_VERSION, board_key

if False:  # typing only; MicroPython never imports typing (the block is compiled away)
    from collections.abc import MutableSequence
    from typing import Any, Protocol

    from firmware.can import Frame
    from firmware.hal import Storage
    from firmware.net import ByteReader, ClosingWriter

    Request = dict[str, Any]  # a JSON request of link A, or its reply

    class Sock(Protocol):
        """A blocking socket (``socket.socket``; emulator/parts/bench.py passes its own)."""

        def sendall(self, data: bytes) -> None: ...

        def recv(self, n: int) -> bytes: ...


def heap() -> "tuple[int, int]":
    """The bytes of the heap allocated and free (MicroPython's ``gc``)."""
    return gc.mem_alloc(), gc.mem_free()  # type: ignore[attr-defined]  # MicroPython's gc


class Link:
    """Link B: blocking JSON-line requests to the emulator."""

    def __init__(self, sock: "Sock") -> None:
        self.sock = sock
        self.buf = b""

    def call(self, req: "list[Any]") -> "Any":  # the JSON answer
        self.sock.sendall(json.dumps(req).encode() + b"\n")
        while b"\n" not in self.buf:
            chunk = self.sock.recv(4096)
            if not chunk:
                raise OSError("emulator link closed")
            self.buf += chunk
        i = self.buf.index(b"\n")
        line = self.buf[:i]
        self.buf = self.buf[i + 1:]
        return json.loads(line)


class RemoteStorage:
    def __init__(self, link: Link) -> None:
        self.link = link

    def read(self, name: str) -> "bytes | None":
        got = self.link.call(["read", name])
        return None if got is None else binascii.unhexlify(got)

    def write(self, name: str, data: bytes) -> None:
        self.link.call(["write", name, binascii.hexlify(data).decode()])

    def rename(self, old: str, new: str) -> None:
        self.link.call(["rename", old, new])

    def remove(self, name: str) -> None:
        self.link.call(["remove", name])


class RemoteHal:
    def __init__(self, link: Link, n: int, cause: int, seed: int) -> None:
        self.link = link
        self.n_channels = n
        self.storage: "Storage" = RemoteStorage(link)
        self.cause = cause
        self.now = 0
        self.ma = [0] * n
        self.sw = [False] * n
        self.mv = 0
        self.feeds = 0
        self.rebooted = False
        random.seed(seed)

    def ticks_ms(self) -> int:
        return self.now

    def read_currents_ma(self, out: "MutableSequence[int]") -> None:
        ma = self.ma
        for ch in range(self.n_channels):
            out[ch] = ma[ch]

    def read_current_ma(self, ch: int) -> int:
        return self.ma[ch]

    def set_switch(self, ch: int, on: bool) -> None:
        self.sw = self.link.call(["set_switch", ch, on])  # the read-backs, a JSON list

    def read_switch(self, ch: int) -> bool:
        return self.sw[ch]

    def read_input_mv(self) -> int:
        return self.mv

    def wdt_feed(self) -> None:
        self.feeds += 1

    def reset_cause(self) -> int:
        return self.cause

    def random_bytes(self, n: int) -> bytes:
        return bytes([random.getrandbits(8) for _ in range(n)])

    def reboot(self) -> None:
        self.rebooted = True


class Runner:
    def __init__(self, link: Link) -> None:
        gc.collect()
        self.base = heap()[0]
        self.link = link
        self.app: "App"  # declared, not set: boot (always the first request) sets both
        self.hal: "RemoteHal"
        self.net: "Net | None" = None
        self.tasks: "list[asyncio.Task[None]]" = []
        self.can_cfg: "Request | None" = None
        self.can: "CanNode | None" = None

    async def boot(self, req: "Request") -> "Request":
        hal = RemoteHal(self.link, req["n"], req["cause"], req["seed"])
        app = App(hal, req.get("factory"))
        self.hal = hal
        self.app = app
        app.start()
        if self.net is None:
            self.net = Net(app, FIRMWARE_VERSION, req.get("caps", 0))
            await self.net.serve_tcp("127.0.0.1", req["tcp"])
            if req.get("modbus"):  # behind the emulator's link proxy, which names clients
                await modbus.serve(self.net, "127.0.0.1", req["modbus"], proxied=True)
            if req.get("tug"):
                await tug.serve(self.net, "127.0.0.1", req["tug"], bool(req.get("tug_switch")))
            if req.get("serial"):  # the emulator relays its pty here, byte for byte
                await asyncio.start_server(self._serial, "127.0.0.1", req["serial"])
            self.tasks.append(asyncio.create_task(self.net.housekeeping()))
            self.can_cfg = req.get("can")
        else:
            self.net.attach(app)
        cfg = self.can_cfg
        if cfg:
            self.can = CanNode(app.board, board_key(app.board), hal.random_bytes, cfg["node"],
                               cfg["rate"])
        return {"ok": 1}

    async def _serial(self, reader: "ByteReader", writer: "ClosingWriter") -> None:
        await self.net.serve_serial(reader, writer)  # type: ignore[union-attr]  # booted: set
        writer.close()

    def can_frames(self, frames: "list[Frame]") -> "list[list[Any]]":
        return [[can_id, binascii.hexlify(data).decode()] for can_id, data in frames]

    def can_rx(self, req: "Request") -> "Request":
        if self.can is None:
            return {"frames": []}
        data = binascii.unhexlify(req["data"])
        return {"frames": self.can_frames(self.can.receive(req["id"], data,
                                                           self.hal.now))}

    def step(self, req: "Request") -> "Request":
        hal = self.hal
        app = self.app
        hal.now = req["t"]
        hal.ma = req["ma"]
        hal.sw = req["sw"]
        hal.mv = req["mv"]
        hal.feeds = 0
        due = app.step()
        self.net.pump(hal.now)  # type: ignore[union-attr]  # booted: net is set
        rep: "Request" = {"due": due, "feeds": hal.feeds, "reboot": hal.rebooted}
        if self.can is not None:
            rep["can"] = self.can_frames(self.can.poll(hal.now))
        return rep

    def call(self, req: "Request") -> "Request":
        board = self.app.board
        return {"r": getattr(board, req["m"])(*req["a"])}

    async def serve(self, host: str, port: int) -> None:
        reader, writer = await asyncio.open_connection(host, port)
        writer.write(b"A\n")
        await writer.drain()
        while True:
            line = await reader.readline()
            if not line:
                return
            req = json.loads(line)
            op = req["op"]
            if op == "step":
                rep = self.step(req)
            elif op == "boot":
                rep = await self.boot(req)
            elif op == "can":
                rep = self.can_rx(req)
            elif op == "halt":
                self.net.halt()  # type: ignore[union-attr]  # booted: net is set
                self.can = None
                rep = {"ok": 1}
            elif op == "mem":
                gc.collect()
                alloc, free = heap()
                rep = {"alloc": alloc - self.base, "free": free}
            else:
                rep = self.call(req)
            writer.write(json.dumps(rep).encode() + b"\n")
            await writer.drain()


def main(host: str, port: int) -> None:
    """Connect link B (blocking), then serve link A on asyncio; each names itself first."""
    sock = socket.socket()
    sock.connect(socket.getaddrinfo(host, port)[0][-1])
    sock.sendall(b"B\n")
    asyncio.run(Runner(Link(sock)).serve(host, port))


if __name__ == "__main__":
    main(sys.argv[1], int(sys.argv[2]))
