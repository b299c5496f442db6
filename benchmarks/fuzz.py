"""Fuzz every front end of a running emulated board; count crashes, hangs and channel changes.

Run with the project's Python (``.venv/bin/python benchmarks/fuzz.py [--frames N] [--seed S]
[--runtime cpython|micropython] [--only tcp,serial,modbus,can,tug] [--write]``). It starts one
``dxboard emulate models/tedusar`` with every front end (native TCP, serial on a pty, Modbus
TCP, CAN on a udp_multicast bus, the original TEDUSAR format) and a key the fuzzer never
learns, waits until the board has settled, then sends each front end its share of the frames
of ``benchmarks/fuzz_frames.py`` (random, mutated, truncated, oversized, valid framing with
invalid fields) in batches. After every batch it checks:

- **crashes**: the emulator process died, it printed a traceback, or the board rebooted
  (the boot count of its control endpoint went up);
- **hangs**: the front end did not answer a good request within ``PROBE_S`` (native: a
  fresh session's HELLO and PING/PONG; serial: HELLO_REQUEST/HELLO; Modbus: a read of the
  input registers; CAN: a DXB_CmdResult to a command with a wrong tag; tug: a REQUEST for
  the specifications);
- **changes**: every EVENT about a channel (a state change, trip, fault or shed) that the
  harness's own observer session receives while a front end is fuzzed, plus any channel whose
  commanded state, read-back or state differs afterwards: with no authenticated command sent
  and no fault injected, any change is the fuzzer's doing. The observer proves the key once
  (AUTH_PING) so that the fuzzer's connections can never evict it; the frames never use it.

Bounded by ``--frames`` (default 1,000,000 in all, split evenly) and ``--seconds``. Prints a
Markdown section; ``--write`` replaces the ``## Fuzzing the front ends`` section of
``benchmarks/RESULTS.md``. ``run()`` is also what the small version in the tests calls.
"""

from __future__ import annotations

import argparse
import contextlib
import json
import os
import platform
import random
import re
import socket
import struct
import subprocess
import sys
import tempfile
import threading
import time
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

import can as pycan  # noqa: E402
import serial  # noqa: E402

from benchmarks import fuzz_frames as ff  # noqa: E402
from host.commands.inject import request as control_request  # noqa: E402
from protocol.connection import HOST, Connection  # noqa: E402
from protocol.constants import BOARD_CHANNEL, EV_REBOOT  # noqa: E402
from protocol.messages import AuthPing, Event, Hello, HelloRequest, Ping, Pong  # noqa: E402

FRONTS = ("tcp", "serial", "modbus", "can", "tug")
BATCH = 250
PROBE_S = 10.0
CAN_PROBES = 3  # probes sent before a CAN front end counts as hung (the bus loses datagrams)
SETTLE_S = 2.0
KEY_HEX = os.urandom(32).hex()  # the board's: only the observer uses it, never the fuzzer


def _udp_port() -> int:
    """A UDP port the kernel gave nobody else just now (its own choice for a bind to 0)."""
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


class Board:
    """``dxboard emulate`` with every front end; its control endpoint tells the truth."""

    def __init__(self, runtime: str) -> None:
        group = f"239.74.{random.randrange(1, 250)}.{random.randrange(1, 250)}"
        self.err = tempfile.TemporaryFile(mode="w+")  # noqa: SIM115 (closed by stop)
        # a UDP port of this run's own for the bus (python-can reads $CAN_CONFIG): Linux hands
        # a multicast datagram to every socket bound to its port, whatever group it joined
        self.can_port = _udp_port()
        env = {**os.environ, "DXBOARD_KEY": KEY_HEX, "PYTHONPATH": str(ROOT),
               "CAN_CONFIG": json.dumps({"port": self.can_port})}
        self.proc = subprocess.Popen(
            [sys.executable, "-m", "host.cli", "emulate", str(ROOT / "models" / "tedusar"),
             "--runtime", runtime, "--modbus", "127.0.0.1:0", "--serial",
             "--can", f"udp_multicast:{group}", "--tug", "127.0.0.1:0"],
            stdout=subprocess.PIPE, stderr=self.err, text=True, env=env, cwd=ROOT)
        self.urls: dict[str, str] = {}
        assert self.proc.stdout is not None
        while len(self.urls) < 6:  # board, control, modbus, serial, can, tug
            line = self.proc.stdout.readline()
            if not line:
                raise RuntimeError("dxboard emulate did not start: " + self.errors())
            name, _, url = line.strip().partition(": ")
            self.urls[name] = url
        self.group = group

    def address(self, name: str) -> tuple[str, int]:
        host, _, port = self.urls[name].split("://", 1)[1].rpartition(":")
        return host, int(port)

    def control(self, req: dict[str, Any]) -> dict[str, Any]:
        return control_request(self.urls["control"], req)

    def snapshot(self) -> tuple[int, list[tuple[bool, bool, str]]]:
        st = self.control({"op": "status"})["status"]
        return st["boots"], [(c["commanded"], c["physical"], c["state"]) for c in st["channels"]]

    def errors(self) -> str:
        self.err.seek(0)
        return self.err.read()

    def stop(self) -> None:
        if self.proc.poll() is None:
            self.proc.terminate()
            try:
                self.proc.wait(10)
            except subprocess.TimeoutExpired:
                self.proc.kill()
                self.proc.wait()
        self.err.close()


class Observer:
    """The harness's own session on the board: it proves the key (AUTH_PING, so the board
    never evicts it for the fuzzer's connections) and counts every EVENT the board pushes
    about a channel (state, trip, fault, shed) and every reboot; nothing else is sent."""

    def __init__(self, board: Board) -> None:
        self.sock = socket.create_connection(board.address("board"), timeout=10)
        self.conn = Connection(HOST, bytes.fromhex(KEY_HEX))
        self.channel_events = 0
        self.reboots = 0
        self.lost = False
        self.lock = threading.Lock()
        self._stop = threading.Event()
        hello = _recv_until(self.sock, _decoded(self.conn, Hello), PROBE_S)
        assert hello, "no HELLO for the observer"
        self.sock.sendall(self.conn.send(AuthPing(1, req_id=1)))
        threading.Thread(target=self._read, daemon=True).start()
        threading.Thread(target=self._keepalive, daemon=True).start()

    def _read(self) -> None:
        while not self._stop.is_set():
            try:
                data = self.sock.recv(65536)
            except TimeoutError:
                continue
            except OSError:
                data = b""
            if not data:
                self.lost = not self._stop.is_set()
                return
            self.conn.receive_data(data)
            for ev in self.conn.events():
                if isinstance(ev, Event):
                    with self.lock:
                        if ev.channel == BOARD_CHANNEL:
                            self.reboots += ev.kind == EV_REBOOT
                        else:
                            self.channel_events += 1

    def _keepalive(self) -> None:
        n = 2
        while not self._stop.wait(5.0):
            with contextlib.suppress(OSError):
                self.sock.sendall(self.conn.send(Ping(n, req_id=n)))
            n += 1

    def counts(self) -> tuple[int, int]:
        with self.lock:
            return self.channel_events, self.reboots

    def close(self) -> None:
        self._stop.set()
        with contextlib.suppress(OSError):
            self.sock.close()


def _drain(sock: socket.socket) -> None:
    """Read and drop everything (replies and pushes) until the connection ends."""
    with contextlib.suppress(OSError):
        while sock.recv(65536):
            pass


class StreamFront:
    """A TCP front end (native, Modbus, tug): one connection the batches go down (opened
    again when the board closes it, as it may for garbage), drained by a thread."""

    def __init__(self, address: tuple[str, int]) -> None:
        self.address = address
        self.sock: socket.socket | None = None

    def _open(self) -> socket.socket:
        if self.sock is None:
            self.sock = socket.create_connection(self.address, timeout=10)
            threading.Thread(target=_drain, args=(self.sock,), daemon=True).start()
        return self.sock

    def send(self, frames: list[bytes]) -> None:
        for frame in frames:
            for _ in range(2):
                try:
                    self._open().sendall(frame)
                    break
                except OSError:
                    self.close()

    def close(self) -> None:
        if self.sock is not None:
            with contextlib.suppress(OSError):
                self.sock.close()
            self.sock = None


def _recv_until(sock: socket.socket, done: Any, timeout: float) -> bool:
    """Read until ``done(all bytes so far)``; False at the deadline or the end of the stream."""
    end = time.monotonic() + timeout
    data = b""
    while time.monotonic() < end:
        sock.settimeout(max(0.05, end - time.monotonic()))
        try:
            chunk = sock.recv(65536)
        except TimeoutError:
            continue
        except OSError:
            return False
        if not chunk:
            return False
        data += chunk
        if done(data):
            return True
    return False


def _decoded(conn: Connection, kind: type) -> Any:
    """A ``done`` for ``_recv_until``: the bytes hold a message of ``kind``."""
    fed = [0]

    def done(data: bytes) -> bool:
        conn.receive_data(data[fed[0]:])
        fed[0] = len(data)
        return any(isinstance(e, kind) for e in conn.events())

    return done


def probe_tcp(board: Board) -> bool:
    conn = Connection(HOST)
    with socket.create_connection(board.address("board"), timeout=PROBE_S) as s:
        if not _recv_until(s, _decoded(conn, Hello), PROBE_S):
            return False
        s.sendall(conn.send(Ping(7, req_id=1)))
        return _recv_until(s, _decoded(conn, Pong), PROBE_S)


class SerialFront:
    def __init__(self, path: str) -> None:
        self.port = serial.Serial(path, 115200, timeout=0)
        self.conn = Connection(HOST)

    def send(self, frames: list[bytes]) -> None:
        for frame in frames:
            self.port.write(frame)
            self.port.read(65536)  # keep the board's replies from backing up

    def probe(self) -> bool:
        """HELLO_REQUEST until a HELLO answers. The board drops a partial frame after 250 ms
        of silence *as it receives*: a request that reaches it sooner after the fuzz (a busy
        board reads late) continues that frame, so a host asks again after a pause, as
        PROTOCOL.md §2 lets it."""
        end = time.monotonic() + PROBE_S
        n = 0
        while time.monotonic() < end:
            time.sleep(0.3)
            self.port.read(1 << 20)
            n += 1
            self.conn = Connection(HOST)
            self.port.write(self.conn.send(HelloRequest(req_id=4000 + n)))
            again = time.monotonic() + 1.0
            while time.monotonic() < min(again, end):
                self.conn.receive_data(self.port.read(65536))
                if any(isinstance(e, Hello) and e.req_id == 4000 + n
                       for e in self.conn.events()):
                    return True
                time.sleep(0.01)
        return False

    def close(self) -> None:
        self.port.close()


def probe_modbus(board: Board) -> bool:
    with socket.create_connection(board.address("modbus"), timeout=PROBE_S) as s:
        s.sendall(struct.pack(">HHHBBHH", 9, 0, 6, 1, 4, 100, 10))
        return _recv_until(s, lambda d: len(d) >= 9 + 20, PROBE_S)


def probe_tug(board: Board) -> bool:
    with socket.create_connection(board.address("tug"), timeout=PROBE_S) as s:
        s.sendall(struct.pack("<BBHB", 0x02, 3, 1, 0))  # REQUEST the specifications
        return _recv_until(s, lambda d: b"\x02\x00" in d, PROBE_S)


class CanFront:
    def __init__(self, group: str, port: int) -> None:
        self.bus = pycan.Bus(interface="udp_multicast", channel=group, port=port,
                             receive_own_messages=False)

    def send(self, frames: list[tuple[int, bytes]]) -> None:
        for can_id, data in frames:
            with contextlib.suppress(pycan.CanError):
                self.bus.send(pycan.Message(arbitration_id=can_id, data=data,
                                            is_extended_id=False))

    def probe(self) -> bool:
        """The probe is a command with a wrong tag, whose answer is error 201. The board may
        still be answering the last batch (other results, other codes): those are skipped, not
        taken for the probe's answer. The bus is lossy (UDP multicast drops datagrams when a
        reader's buffer is full, as it is right after a batch on a busy machine), so the probe
        is sent up to ``CAN_PROBES`` times: a hang is a board that answers none of them."""
        for _ in range(CAN_PROBES):
            while self.bus.recv(0) is not None:
                pass
            for can_id, data in ((0x180, struct.pack("<BBBBI", 1, 8, 0, 0, 1)),
                                 (0x181, bytes(8)), (0x182, bytes(8))):
                self.bus.send(pycan.Message(arbitration_id=can_id, data=data,
                                            is_extended_id=False))
            end = time.monotonic() + PROBE_S
            while time.monotonic() < end:
                msg = self.bus.recv(0.2)
                if msg is not None and msg.arbitration_id == 0x188 and \
                        bytes(msg.data[:2]) == b"\x01\x08" and \
                        struct.unpack_from("<H", msg.data, 2)[0] == 201:
                    return True
        return False

    def close(self) -> None:
        self.bus.shutdown()


def run(frames: int = 1_000_000, seed: int = 1, runtime: str = "cpython",
        only: tuple[str, ...] = FRONTS, seconds: float = 3600.0,
        verbose: bool = False) -> dict[str, Any]:
    """Fuzz ``only`` with ``frames`` in all; per front end: frames, crashes, hangs, changes."""
    rng = random.Random(seed)
    board = Board(runtime)
    out: dict[str, Any] = {"runtime": runtime, "seed": seed, "fronts": {}}
    try:
        time.sleep(SETTLE_S)  # the power-up queue switches the pc on first
        fronts: dict[str, Any] = {}
        for name in only:
            if name == "tcp":
                fronts[name] = StreamFront(board.address("board"))
            elif name == "serial":
                fronts[name] = SerialFront(board.urls["serial"].removeprefix("serial://"))
            elif name == "modbus":
                fronts[name] = StreamFront(board.address("modbus"))
            elif name == "can":
                fronts[name] = CanFront(board.group, board.can_port)
            else:
                fronts[name] = StreamFront(board.address("tug"))
        probes = {"tcp": lambda: probe_tcp(board), "modbus": lambda: probe_modbus(board),
                  "tug": lambda: probe_tug(board), "serial": lambda: fronts["serial"].probe(),
                  "can": lambda: fronts["can"].probe()}
        share = frames // len(only)
        deadline = time.monotonic() + seconds
        observer = Observer(board)
        baseline = board.snapshot()
        try:
            for name in only:
                stats = {"frames": 0, "crashes": 0, "hangs": 0, "changes": 0, "seconds": 0.0}
                out["fronts"][name] = stats
                events0, reboots0 = observer.counts()
                t0 = time.monotonic()
                while stats["frames"] < share and time.monotonic() < deadline:
                    n = min(BATCH, share - stats["frames"])
                    fronts[name].send(ff.GENERATORS[name](rng, n))
                    stats["frames"] += n
                    if board.proc.poll() is not None:
                        stats["crashes"] += 1
                        raise RuntimeError(f"the emulator died: {board.errors()[-2000:]}")
                    if not probes[name]():
                        stats["hangs"] += 1
                    if verbose:
                        print(f"{name}: {stats}", file=sys.stderr, flush=True)
                stats["seconds"] = round(time.monotonic() - t0, 2)
                time.sleep(1.0)  # what the last batch did shows up before the count
                now = board.snapshot()
                events, reboots = observer.counts()
                stats["changes"] = events - events0 + sum(
                    a != b for a, b in zip(now[1], baseline[1], strict=True))
                stats["crashes"] += reboots - reboots0 + (now[0] - baseline[0])
                if observer.lost:
                    stats["crashes"] += 1
                    observer = Observer(board)
                baseline = now
                with contextlib.suppress(Exception):
                    fronts[name].close()
        finally:
            observer.close()
    finally:
        out["tracebacks"] = board.errors().count("Traceback")
        if out["tracebacks"]:
            out["errors"] = board.errors()[-3000:]
        board.stop()
    return out


def markdown(results: list[dict[str, Any]]) -> str:
    lines = ["## Fuzzing the front ends", "",
             f"`benchmarks/fuzz.py` on {platform.python_implementation()} "
             f"{platform.python_version()}, {os.cpu_count()} cores (shared); one "
             "`dxboard emulate models/tedusar` with every front end, frames of five kinds "
             "(random, mutated, truncated, oversized, valid framing with invalid fields) in "
             f"batches of {BATCH}, each batch followed by a probe of the front end and a look at "
             "every channel. Crashes: the emulator died, printed a traceback or rebooted; "
             f"hangs: no answer to a good request within {PROBE_S:g} s; changes: a channel's "
             "command, read-back or state changed (no authenticated command was sent).", "",
             "| runtime | front end | frames | seconds | frames/s | crashes | hangs | changes |",
             "|---|---|---|---|---|---|---|---|"]
    total = 0
    for res in results:
        for name, st in res["fronts"].items():
            rate = st["frames"] / st["seconds"] if st["seconds"] else 0
            lines.append(f"| {res['runtime']} | {name} | {st['frames']:,} | {st['seconds']} | "
                         f"{rate:,.0f} | {st['crashes']} | {st['hangs']} | {st['changes']} |")
            total += st["frames"]
        lines.append(f"| {res['runtime']} | tracebacks in the emulator's output | | | | "
                     f"{res['tracebacks']} | | |")
    lines += ["", f"{total:,} frames in all."]
    return "\n".join(lines) + "\n"


def write(section: str) -> None:
    path = ROOT / "benchmarks" / "RESULTS.md"
    text = path.read_text()
    pattern = re.compile(r"## Fuzzing the front ends\n.*?(?=\n## |\Z)", re.S)
    text = pattern.sub(section.rstrip("\n") + "\n", text) if pattern.search(text) \
        else text.rstrip("\n") + "\n\n" + section
    path.write_text(text)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--frames", type=int, default=1_000_000, help="frames in all, per runtime")
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--runtime", default="cpython", help="cpython, micropython or both")
    ap.add_argument("--only", default=",".join(FRONTS), help="front ends, comma-separated")
    ap.add_argument("--seconds", type=float, default=3600.0, help="time limit per runtime")
    ap.add_argument("--write", action="store_true", help="update benchmarks/RESULTS.md")
    ap.add_argument("-v", "--verbose", action="store_true", help="a line per batch")
    args = ap.parse_args()
    runtimes = ("cpython", "micropython") if args.runtime == "both" else (args.runtime,)
    only = tuple(x for x in args.only.split(",") if x)
    results = [run(args.frames, args.seed, rt, only, args.seconds, args.verbose)
               for rt in runtimes]
    section = markdown(results)
    print(section)
    for res in results:
        if res.get("errors"):
            print(res["errors"], file=sys.stderr)
    if args.write:
        write(section)


if __name__ == "__main__":
    main()
