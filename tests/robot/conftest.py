"""The virtual robot as users run it: ``dxboard emulate DIR --robot``, node processes, zenoh.

``robot_dir`` is a copy of ``models/tedusar`` with short boot times (the board's devices boot in
0.2-1.5 s instead of 1-5 s) so the tests stay quick; everything else is the real model.
``Robot`` is the emulator subprocess with its URLs; ``Topics`` is the test's own zenoh peer,
listening where the nodes connect (``DXBOARD_ZENOH``), recording every message it sees;
``Nodes`` starts ``python -m emulator.robot.node NAME DIR`` processes and stops them.
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

ROOT = Path(__file__).resolve().parents[2]
TEDUSAR = ROOT / "models" / "tedusar"
DXBOARD = str(Path(sys.executable).parent / "dxboard")
KEY_HEX = "000102030405060708090a0b0c0d0e0f"
BOOT_MS = {"hokuyo": 1500, "jaguar": 300, "laser_alignment": 300}


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        port: int = s.getsockname()[1]
        return port


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


class Robot:
    """One ``dxboard emulate DIR --robot [EXTRA...]`` process: board, control and device URLs
    (and ``world`` with ``--world``)."""

    def __init__(self, system_dir: Path, *extra: str) -> None:
        self.env = {**os.environ, "DXBOARD_KEY": KEY_HEX}
        self.proc = subprocess.Popen([DXBOARD, "emulate", str(system_dir), "--robot", *extra],
                                     stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                                     env=self.env, cwd=ROOT)
        self.urls: dict[str, str] = {}
        self.devices: dict[str, str] = {}
        n = len(yaml.safe_load((system_dir / "robot.yaml").read_text())["devices"])
        assert self.proc.stdout is not None
        while len(self.devices) < n or ("--world" in extra and "world" not in self.urls):
            line = self.proc.stdout.readline()
            if not line:
                err = self.proc.stderr.read() if self.proc.stderr else ""
                raise RuntimeError(f"dxboard emulate --robot did not start: {err}")
            name, _, url = line.strip().partition(": ")
            if name == "device":
                dev, _, url = url.partition(" ")
                self.devices[dev] = url
            else:
                self.urls[name] = url

    def port(self, device: str) -> int:
        return int(self.devices[device].rsplit(":", 1)[1])

    def board(self, *args: str) -> str:
        p = subprocess.run([DXBOARD, "board", self.urls["board"], *args], capture_output=True,
                           text=True, env=self.env, timeout=20)
        assert p.returncode == 0, p.stderr
        return p.stdout

    def inject(self, channel: str, fault: str, *params: str) -> None:
        p = subprocess.run([DXBOARD, "inject", self.urls["control"], channel, fault, *params],
                           capture_output=True, text=True, timeout=20)
        assert p.returncode == 0, p.stderr

    def channel(self, name: str) -> dict[str, Any]:
        status = json.loads(self.board("status", "--json"))
        found: dict[str, Any] = next(c for c in status["state"]["channels"]
                                     if c["name"] == name)
        return found

    def stop(self) -> int:
        if self.proc.poll() is None:
            self.proc.send_signal(signal.SIGTERM)
            try:
                self.proc.wait(10)
            except subprocess.TimeoutExpired:
                self.proc.kill()
                self.proc.wait(10)
        return self.proc.returncode


class Topics:
    """The test's zenoh peer: listens on ``endpoint``, records (time, topic, values) of all."""

    def __init__(self) -> None:
        self.endpoint = f"tcp/127.0.0.1:{free_port()}"
        cfg = zenoh.Config()
        cfg.insert_json5("mode", '"peer"')
        cfg.insert_json5("scouting/multicast/enabled", "false")
        cfg.insert_json5("listen/endpoints", json.dumps([self.endpoint]))
        cfg.insert_json5("connect/endpoints", "[]")
        self.session = zenoh.open(cfg)
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
        """Messages on ``topic`` during the next ``seconds``."""
        t0 = time.monotonic()
        time.sleep(seconds)
        return len(self.messages(topic, t0, time.monotonic()))

    def wait_for(self, topic: str, timeout: float = 10.0) -> float:
        """Wait for a new message on ``topic``; returns how long that took."""
        t0 = time.monotonic()
        while time.monotonic() - t0 < timeout:
            if self.messages(topic, t0):
                return time.monotonic() - t0
            time.sleep(0.05)
        raise AssertionError(f"no {topic} within {timeout} s")

    def close(self) -> None:
        self.sub.undeclare()  # type: ignore[no-untyped-call]  # zenoh stub
        self.session.close()  # type: ignore[no-untyped-call]


class Nodes:
    """Node processes: ``python -m emulator.robot.node NAME DIR``, stopped at the end."""

    def __init__(self, system_dir: Path, robot: Robot, topics: Topics) -> None:
        self.system_dir = system_dir
        self.env = {**os.environ, "DXBOARD_ZENOH": topics.endpoint,
                    "DXBOARD_DEVICES": json.dumps(robot.devices),
                    "PYTHONPATH": str(ROOT)}
        self.procs: dict[str, subprocess.Popen[str]] = {}

    def start(self, *names: str) -> None:
        for name in names:
            self.procs[name] = subprocess.Popen(
                [sys.executable, "-m", "emulator.robot.node", name, str(self.system_dir)],
                stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True, env=self.env,
                cwd=ROOT)

    def running(self, name: str) -> bool:
        return self.procs[name].poll() is None

    def stop(self, name: str) -> int:
        p = self.procs[name]
        if p.poll() is None:
            p.send_signal(signal.SIGTERM)
            try:
                p.wait(10)
            except subprocess.TimeoutExpired:
                p.kill()
                p.wait(10)
        return p.returncode

    def log(self, name: str) -> str:
        p = self.procs[name]
        self.stop(name)
        return p.stderr.read() if p.stderr else ""

    def stop_all(self) -> None:
        for name in self.procs:
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
