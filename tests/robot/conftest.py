"""The virtual robot as users run it: ``dxboard emulate DIR --robot``, node processes, zenoh.

``robot_dir`` is a copy of ``models/tedusar`` with short boot times (the board's devices boot in
0.2-1.5 s instead of 1-5 s) so the tests stay quick; everything else is the real model.
``Robot`` is the emulator subprocess with its URLs; ``Conn`` a client of one of its devices;
``Topics`` is the test's own zenoh peer, listening where the nodes connect (``DXBOARD_ZENOH``),
recording every message it sees; ``Nodes`` starts ``python -m emulator.robot.node NAME DIR``
processes and stops them. Every wait is on a condition with a generous deadline
(``tests.wait``); windows of fixed length are used only to show that nothing arrives.
"""

from __future__ import annotations

import json
import os
import shutil
import signal
import socket
import subprocess
import sys
import threading
import time
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import pytest
import yaml
import zenoh

from host.commands.inject import request
from host.launch.boards import RunningBoard
from host.launch.procs import Child
from tests.ports import clashed, zenoh_endpoint
from tests.wait import wait_until

ROOT = Path(__file__).resolve().parents[2]
TEDUSAR = ROOT / "models" / "tedusar"
DXBOARD = str(Path(sys.executable).parent / "dxboard")
KEY_HEX = "000102030405060708090a0b0c0d0e0f"
BOOT_MS = {"hokuyo": 1500, "jaguar": 300, "laser_alignment": 300}


@pytest.fixture
def robot_dir(tmp_path: Path) -> Path:
    d = tmp_path / "tedusar"
    shutil.copytree(TEDUSAR, d)
    emu = yaml.safe_load((d / "emulator.yaml").read_text())
    for ch in emu["channels"]:
        if ch["name"] in BOOT_MS:
            ch["boot_ms"] = BOOT_MS[ch["name"]]
    (d / "emulator.yaml").write_text(yaml.safe_dump(emu))
    return d


class Robot(RunningBoard):
    """One ``dxboard emulate DIR --robot [EXTRA...]`` process (the launcher's ``RunningBoard``)
    with the tests' key: board, control and device URLs (and ``world`` with ``--world``), and
    what a test asks of it."""

    def __init__(self, system_dir: Path, *extra: str) -> None:
        super().__init__(system_dir, *extra, key=bytes.fromhex(KEY_HEX))

    def port(self, device: str) -> int:
        return int(self.devices[device].rsplit(":", 1)[1])

    def now_ms(self) -> int:
        """The emulator's clock, the one every device frame's ``t_ms`` is stamped with."""
        rep = request(self.urls["control"], {"op": "status"})
        assert rep["ok"], rep
        return int(rep["status"]["now_ms"])

    def channel(self, name: str) -> dict[str, Any]:
        status = json.loads(self.board("status", "--json"))
        found: dict[str, Any] = next(c for c in status["state"]["channels"]
                                     if c["name"] == name)
        return found


class Conn:
    """A client of one device: JSON lines in, lines out."""

    def __init__(self, port: int) -> None:
        self.sock = socket.create_connection(("127.0.0.1", port), timeout=30)
        self.buf = b""
        self.closed = False

    def read(self, seconds: float) -> list[dict[str, Any]]:
        """Every frame received during ``seconds``."""
        end = time.monotonic() + seconds
        out: list[dict[str, Any]] = []
        while time.monotonic() < end and not self.closed:
            out += self._recv(end - time.monotonic())
        return out

    def _recv(self, timeout: float) -> list[dict[str, Any]]:
        self.sock.settimeout(max(0.01, timeout))
        try:
            data = self.sock.recv(65536)
        except TimeoutError:
            return []
        except ConnectionError:
            data = b""
        if not data:
            self.closed = True
        self.buf += data
        *lines, self.buf = self.buf.split(b"\n")
        return [json.loads(line) for line in lines]

    def frames(self, n: int, timeout: float = 30.0) -> list[dict[str, Any]]:
        """The next ``n`` frames (at least), however long a busy machine takes for them."""
        got: list[dict[str, Any]] = []
        wait_until(lambda: len(got) >= n or self.closed or got.extend(self._recv(0.2)),
                   timeout, f"{n} frames", interval=0, show=lambda: f"{len(got)} frames")
        assert len(got) >= n, f"the device closed the connection after {len(got)} frames"
        return got

    def wait_quiet(self, quiet_s: float, timeout: float = 30.0) -> list[dict[str, Any]]:
        """Read until nothing has arrived for ``quiet_s``; the frames read until then."""
        got: list[dict[str, Any]] = []

        def quiet() -> bool:
            frames = self.read(quiet_s)
            got.extend(frames)
            return not frames

        wait_until(quiet, timeout, f"{quiet_s} s without a frame", interval=0,
                   show=lambda: f"{len(got)} frames, last {got[-1:]}")
        return got

    def wait_closed(self, timeout: float = 30.0) -> None:
        def closed() -> bool:
            if not self.closed:
                self._recv(0.2)
            return self.closed

        wait_until(closed, timeout, "the device to close the connection", interval=0)

    def send(self, obj: object) -> None:
        self.sock.sendall(json.dumps(obj).encode() + b"\n")

    def close(self) -> None:
        self.sock.close()


def serving(robot: Robot, device: str, timeout: float = 30.0) -> Conn:
    """A connection to ``device`` once it is powered, booted and sending frames."""
    conn: list[Conn] = []

    def up() -> bool:
        try:
            c = Conn(robot.port(device))
        except ConnectionRefusedError:
            return False
        if c.read(1.0):
            conn.append(c)
            return True
        c.close()
        return False

    wait_until(up, timeout, f"{device} serving frames")
    return conn[0]


class Topics:
    """The test's zenoh peer: listens on ``endpoint``, records (time, topic, values) of all."""

    def __init__(self) -> None:
        for _ in range(5):  # another process took the port meanwhile: take a fresh one
            self.endpoint = zenoh_endpoint()
            cfg = zenoh.Config()
            cfg.insert_json5("mode", '"peer"')
            cfg.insert_json5("scouting/multicast/enabled", "false")
            cfg.insert_json5("listen/endpoints", json.dumps([self.endpoint]))
            cfg.insert_json5("connect/endpoints", "[]")
            try:
                self.session = zenoh.open(cfg)
                break
            except zenoh.ZError as exc:
                if not clashed(str(exc)):
                    raise
        self.lock = threading.Lock()
        self.seen: list[tuple[float, str, dict[str, Any]]] = []
        self.sub = self.session.declare_subscriber("**", self._on)

    def _on(self, sample: zenoh.Sample) -> None:
        values = json.loads(sample.payload.to_bytes())
        with self.lock:
            self.seen.append((time.monotonic(), "/" + str(sample.key_expr), values))

    def messages(self, topic: str, since: float = 0.0,
                 until: float = float("inf")) -> list[dict[str, Any]]:
        with self.lock:
            return [v for t, k, v in self.seen if k == topic and since <= t < until]

    def count_over(self, topic: str, seconds: float) -> int:
        """Messages on ``topic`` during the next ``seconds`` (to show that none arrive)."""
        t0 = time.monotonic()
        time.sleep(seconds)
        return len(self.messages(topic, t0, time.monotonic()))

    def collect(self, topic: str, n: int, timeout: float = 30.0) -> list[dict[str, Any]]:
        """The next ``n`` messages on ``topic``, however long a busy machine takes."""
        t0 = time.monotonic()
        got = wait_until(lambda: self.messages(topic, t0)[:n] if len(self.messages(topic, t0))
                         >= n else [], timeout, f"{n} messages on {topic}",
                         show=lambda: f"{len(self.messages(topic, t0))} messages")
        return got

    def arrivals(self, topic: str, since: float = 0.0) -> list[float]:
        """When each message on ``topic`` arrived here (monotonic seconds)."""
        with self.lock:
            return [t for t, k, _ in self.seen if k == topic and t >= since]

    def wait_for(self, topic: str, timeout: float = 30.0) -> None:
        """Wait for a new message on ``topic``."""
        self.collect(topic, 1, timeout)

    def wait_silent(self, topic: str, quiet_s: float, timeout: float = 30.0) -> None:
        """Wait until ``topic`` has been silent for ``quiet_s`` (it stopped, or never began)."""
        t0 = time.monotonic()

        def silent() -> bool:
            last = max([t0, *self.arrivals(topic, t0)])
            return time.monotonic() - last >= quiet_s

        wait_until(silent, timeout, f"{topic} silent for {quiet_s} s",
                   show=lambda: f"{len(self.messages(topic, t0))} messages since")

    def wait_peers(self, n: int, timeout: float = 30.0) -> None:
        """Wait until ``n`` node processes are connected to this peer (they are up)."""
        wait_until(lambda: len(self.session.info.peers_zid()) >= n, timeout,
                   f"{n} zenoh peers", show=lambda: len(self.session.info.peers_zid()))

    def close(self) -> None:
        self.sub.undeclare()  # type: ignore[no-untyped-call]  # zenoh stub
        self.session.close()  # type: ignore[no-untyped-call]


class Nodes:
    """Node processes: ``python -m emulator.robot.node NAME DIR [EXTRA]``, each a launcher's
    ``host.launch.procs.Child``, stopped at the end (SIGTERM, SIGKILL if one hangs)."""

    def __init__(self, system_dir: Path, robot: Robot, topics: Topics) -> None:
        self.system_dir = system_dir
        self.env = {**os.environ, "DXBOARD_ZENOH": topics.endpoint,
                    "DXBOARD_DEVICES": json.dumps(robot.devices),
                    "PYTHONPATH": str(ROOT)}
        self.children: dict[str, Child] = {}

    @property
    def procs(self) -> dict[str, subprocess.Popen[bytes]]:
        return {name: c.proc for name, c in self.children.items()}

    def start(self, *names: str, extra: tuple[str, ...] = ()) -> None:
        for name in names:
            self.children[name] = Child(
                [sys.executable, "-m", "emulator.robot.node", name, str(self.system_dir),
                 *extra], env=self.env, cwd=ROOT, name=name, keep_err=100000)

    def running(self, name: str) -> bool:
        return self.children[name].running()

    def stop(self, name: str) -> int:
        return self.children[name].stop(signal.SIGTERM, 10)

    def log(self, name: str) -> str:
        """Its stderr (once stopped)."""
        self.stop(name)
        return "".join(line + "\n" for line in self.children[name].err_tail)

    def stop_all(self) -> None:
        for name in self.children:
            self.stop(name)


@pytest.fixture
def robot(robot_dir: Path) -> Iterator[Robot]:
    r = Robot(robot_dir)
    yield r
    r.stop()


@pytest.fixture
def topics() -> Iterator[Topics]:
    t = Topics()
    yield t
    t.close()


@pytest.fixture
def nodes(robot_dir: Path, robot: Robot, topics: Topics) -> Iterator[Nodes]:
    n = Nodes(robot_dir, robot, topics)
    yield n
    n.stop_all()
