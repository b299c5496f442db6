"""The board on the bench: the shipped ``boot.py`` and ``main.py`` on part models, in lock-step.

``micropython -m emulator.parts.bench HOST PORT REV TCP MODBUS`` (started by
``emulator/board_rt.py``, with ``emulator/parts/clock`` and ``emulator/parts`` first on
``MICROPYPATH`` and the board's flash directory as its working directory) builds a ``World``
wired from the board revision's data (``firmware/boards``): the sensing parts by
``emulator.parts.wiring.wire``, with this ``Bench`` as their electronics (``source``, ``load``,
``drive``), the switches' enable and status pins the parts do not take, the input divider on its
ADC pin, then
boots the firmware as a board does: ``firmware.boot.run()`` (the network: the wired interface,
whose cable is plugged into the host's loopback), then ``import firmware.main``, unmodified,
which builds its HAL through ``machine`` (the parts' model), reads the flashed ``board_rev`` and
configuration from the working directory, and runs its own ``asyncio`` loop forever.

Lock-step: ``time`` is the World's clock (``emulator/parts/clock/time.py``), which only the
emulator moves. It connects three times to the emulator, each link naming itself first:

- link A (emulator -> board, JSON lines, one reply each): ``{"op": "boot", "cause": C, "t":
  ms, "mv": mv}`` (a power-on, watchdog, soft or brown-out reset at the emulator's time ``t``,
  with the input voltage then: the
  microcontroller restarts, the chips keep their registers; answered once ``main.py`` serves),
  ``{"op": "step", "t": ms, "ma": [..], "sw": [..], "mv": mv}`` (this step's electrical inputs:
  each channel's current through its shunt, each switch's output, the input voltage; the clock
  moves to ``t`` and everything the firmware has due by then runs; answers ``{"at": ms,
  "feeds": 0|1, "reboot": bool}``: the emulator time its next timer is due, whether the
  watchdog was fed, whether the microcontroller reset itself), ``{"op": "part", "ch": CH,
  "fault": NAME, "value": V}`` and ``{"op": "part_clear", "ch": CH}`` (a part-level fault of the
  part that senses channel CH, as ``emulator.parts.wiring`` wired it: a shunt monitor's
  ``nack``, ``stuck_low``, ``reset``, ``stuck``, ``open_shunt``, ``gain``, ``noise``,
  ``die_id``, or a smart switch's ``short``, ``overtemp``, ``open_load`` of that channel),
  ``{"op": "regs", "ch": CH}`` (that chip's registers as it holds them now: ``{"regs": [..]}``,
  what a logic analyser on the bench shows; a smart switch has none), ``{"op": "halt"}`` (held
  in reset: every socket closed, nothing runs until the next boot), ``{"op": "call", "m":
  NAME, "a": [..]}`` (a ``Board`` method: the emulator's status, scenario commands) and
  ``{"op": "mem", "import": [..]}`` (the heap in use after a collection, the modules named
  imported first: before the first boot, the firmware's code apart from its objects).
- link B (board -> emulator): ``["set_switch", ch, on]`` the moment an enable pin changes; the
  answer (every switch's output) is what the status pins then read (``firmware.hal.remote.Link``).
- link U: the UART's wires: ``machine.UART(1)`` is this socket (asyncio on the unix port polls
  only real file descriptors), which the emulator relays to its pty.

The servers ``main.py`` starts go through ``start_server`` here, which listens on the loopback
port the emulator chose for the board's port (7000 -> TCP, 502 -> Modbus, 5000 -> the original
TEDUSAR format, served when the flashed configuration sets ``tug_port`` 5000) and keeps every socket
so that a reset closes them all, as the real board's reset drops every connection. A reset the
firmware makes itself (``machine.reset()``, a starved watchdog) raises ``BoardReset`` out of
its loop; the next link A answer says so, and the emulator boots it again.
"""

import asyncio
import json
import select
import socket
import sys
import time

import machine  # type: ignore[import-not-found]  # the parts' model (emulator/parts/machine.py)

from emulator.parts import sched
from emulator.parts import world as _world
from emulator.parts.wiring import wire
from firmware import boards
from firmware.hal.remote import Link
from protocol.constants import RESET_BROWNOUT, RESET_POWER_ON, RESET_SOFT, RESET_WATCHDOG

# the emulator's reset causes as the rp2 port reports them: a soft reset is machine.reset(),
# which on rp2 goes through the watchdog (the firmware's mark tells them apart); a brown-out
# restarts the RP2040 by its power-on reset
CAUSES = {RESET_POWER_ON: _world.PWRON_RESET, RESET_WATCHDOG: _world.WDT_RESET,
          RESET_SOFT: _world.WDT_RESET, RESET_BROWNOUT: _world.PWRON_RESET}
UART_ID = 1
BOARD_PORTS = (7000, 502, 5000)  # firmware/main.py's TCP_PORT, MODBUS_PORT; tug_port flashed


class Unwind(BaseException):
    """Leave the firmware's loop: the emulator resets the board (``req``: what it sent)."""

    def __init__(self, req: "dict | None") -> None:  # type: ignore[type-arg]
        super().__init__()
        self.req = req


sched.install(asyncio.core)  # type: ignore[attr-defined]  # its times: the World's clock


def _readable(sock: object) -> object:
    """Await until ``sock`` is readable (asyncio's own wait, as its streams use it)."""
    yield asyncio.core._io_queue.queue_read(sock)  # type: ignore[attr-defined]


class Bench:
    def __init__(self, rev: str, a: object, b: "socket.socket", u: object,
                 ports: dict) -> None:  # type: ignore[type-arg]
        self.board = boards.load(rev)
        n = self.board["channels"]
        self.n = n
        self.a = a
        self.abuf = b""
        self.link = Link(b)
        self.u = u
        self.ports = ports
        self.ma = [0] * n
        self.closed = [False] * n
        self.mv = 0
        w = _world.install(_world.World())
        w.lan_cable = True  # type: ignore[attr-defined]  # the host's loopback stands in
        w.lan_ip = "127.0.0.1"  # type: ignore[attr-defined]
        self.world = w
        self.sensed = wire(w, self.board, self)  # per channel (part, input)
        for ch, pin in enumerate(self.board["en_pins"]):
            if pin not in w.outputs:  # a smart switch's IN is wired by its part (wiring.py)
                w.wire_output(pin, self._enable(ch))
        for ch, pin in enumerate(self.board.get("status_pins") or ()):
            w.wire_input(pin, self._status(ch))
        vin = self.board["vin"]
        w.wire_adc(vin["adc_pin"], lambda: self.mv / 1000 / vin["divider"])
        self.socks: list = []  # type: ignore[type-arg]  # every socket the firmware opened
        self.inflight: dict | None = None  # type: ignore[type-arg]
        self.boot_req: dict | None = None  # type: ignore[type-arg]
        self.tasks: list = []  # type: ignore[type-arg]  # the tasks started here
        self.reset = False  # the microcontroller reset itself since the last step
        self.app = None
        self.booted = False
        uart = machine.UART

        def uart_of(id: int, *args: object, **kw: object) -> object:
            return self.u if id == UART_ID else uart(id, *args, **kw)

        machine.UART = uart_of
        asyncio.start_server = self.start_server  # type: ignore[assignment]
        self._watch_app()

    # --- the wiring ----------------------------------------------------------------------

    def source(self, ch: int, ohm: float) -> object:
        """What a sense chip's pins see: the shunt's voltage and the switch's output."""
        def at(t_us: int) -> "tuple[float, float]":
            bus_v = self.mv / 1000 if self.closed[ch] else 0.0
            return self.ma[ch] / 1000 * ohm, bus_v
        return at

    def load(self, ch: int) -> object:
        """What a smart switch's output delivers to channel ``ch``'s load while on (amperes)."""
        def at(t_us: int) -> float:
            return self.ma[ch] / 1000 if self.closed[ch] else 0.0
        return at

    def drive(self, ch: int, level: int) -> None:
        """The electronics after the switch of channel ``ch``: its output on or off."""
        if bool(level) != self.closed[ch]:
            self.closed = self.link.call(["set_switch", ch, bool(level)])

    def follow(self) -> None:
        """A smart switch that protected itself (latched off) opens the electronics' switch."""
        for ch, (part, k) in enumerate(self.sensed):
            on = getattr(part, "on", None)
            if on is not None and self.closed[ch] and not on[k]:
                self.drive(ch, 0)

    def _enable(self, ch: int) -> object:
        def drive(level: int) -> None:
            self.drive(ch, level)
        return drive

    def _status(self, ch: int) -> object:
        return lambda: self.closed[ch]

    def _watch_app(self) -> None:
        """Note the firmware's ``App`` as it starts (for the emulator's ``call``s)."""
        from firmware.app import App

        start = App.start
        bench = self

        def seen(app: object) -> None:
            bench.app = app  # type: ignore[assignment]
            start(app)  # type: ignore[arg-type]

        App.start = seen  # type: ignore[method-assign, assignment]

    # --- main.py's servers ---------------------------------------------------------------

    async def start_server(self, cb: object, host: str, port: int, backlog: int = 5) -> object:
        """``asyncio.start_server`` for ``main.py``: the board's port mapped to the emulator's
        choice, every socket kept for the reset; the first one up answers the boot."""
        s = socket.socket()
        s.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
        s.bind(socket.getaddrinfo(host, self.ports.get(port, port))[0][-1])
        s.listen(backlog)
        s.setblocking(False)
        self.socks.append(s)
        self.tasks.append(asyncio.create_task(self._accept(s, cb)))
        if self.boot_req is not None:
            self.boot_req = None
            self.send({"ok": 1})
            self.tasks.append(asyncio.create_task(self.serve_link()))
        return s

    async def _accept(self, s: object, cb: object) -> None:
        while True:
            await _readable(s)  # type: ignore[misc]
            try:
                c, addr = s.accept()  # type: ignore[attr-defined]
            except OSError:
                continue
            c.setblocking(False)
            self.socks.append(c)
            stream = asyncio.StreamReader(c, {"peername": addr})  # type: ignore[arg-type]
            self.tasks.append(asyncio.create_task(cb(stream, stream)))  # type: ignore[operator]

    def close_all(self) -> None:
        self.tasks = []
        for s in self.socks:
            try:  # noqa: SIM105 (MicroPython has no contextlib)
                s.close()
            except OSError:
                pass
        self.socks = []

    # --- link A --------------------------------------------------------------------------

    def send(self, obj: object) -> None:
        self.a.write(json.dumps(obj).encode() + b"\n")  # type: ignore[attr-defined]

    def _line(self) -> "dict | None":  # type: ignore[type-arg]
        if b"\n" not in self.abuf:
            return None
        i = self.abuf.index(b"\n")
        line = self.abuf[:i]
        self.abuf = self.abuf[i + 1:]
        return json.loads(line)  # type: ignore[no-any-return]

    def read_blocking(self) -> "dict | None":  # type: ignore[type-arg]
        while True:
            req = self._line()
            if req is not None:
                return req
            poller = select.poll()
            poller.register(self.a, select.POLLIN)  # type: ignore[arg-type]
            poller.poll(-1)
            chunk = self.a.recv(4096)  # type: ignore[attr-defined]
            if not chunk:
                return None
            self.abuf += chunk

    async def serve_link(self) -> None:
        """Link A while the firmware runs."""
        while True:
            req = self._line()
            if req is None:
                await _readable(self.a)  # type: ignore[misc]
                chunk = self.a.recv(4096)  # type: ignore[attr-defined]
                if not chunk:
                    raise Unwind(None)
                self.abuf += chunk
                continue
            op = req["op"]
            if op in ("boot", "halt"):
                raise Unwind(req)
            self.inflight = req
            if op == "step":
                rep = await self.step(req)
            else:
                rep = self.answer(req)
            self.inflight = None
            self.send(rep)

    async def step(self, req: dict) -> dict:  # type: ignore[type-arg]
        w = self.world
        self.ma = req["ma"]
        self.closed = req["sw"]
        self.mv = req["mv"]
        fed = w.last_feed_us
        w.set_time(req["t"] * 1000)
        now = w.now_us // 1000
        q = asyncio.core._task_queue  # type: ignore[attr-defined]
        for _ in range(1000):  # everything due by now runs (the step, its pushes, writes)
            await asyncio.sleep_ms(0)  # type: ignore[attr-defined]
            head = q.peek()
            if head is None or time.ticks_diff(head.ph_key, now) > 0:  # type: ignore[attr-defined]
                break
        self.follow()
        head = q.peek()
        at = head.ph_key if head is not None else now + 10
        return {"at": max(at, req["t"] + 1), "feeds": 1 if w.last_feed_us != fed else 0,
                "reboot": False}

    def answer(self, req: dict) -> dict:  # type: ignore[type-arg]
        """Link A requests that run nothing of the firmware's loop."""
        op = req["op"]
        if op == "step":  # held in reset, or reset itself: nothing runs
            self.world.set_time(req["t"] * 1000)
            rep = {"at": req["t"] + 10, "feeds": 0, "reboot": self.reset}
            self.reset = False
            return rep
        if op == "part":
            part, k = self.sensed[req["ch"]]
            if hasattr(part, "regs"):  # a shunt monitor: its faults are the chip's
                part.inject(req["fault"], req["value"], self.world.now_us)
            else:  # a smart switch: its faults are its channel's
                part.inject(req["fault"], k, req["value"])
                self.follow()
            return {"ok": 1}
        if op == "part_clear":
            part, k = self.sensed[req["ch"]]
            if hasattr(part, "regs"):
                part.clear()
            else:  # this channel's faults only: the other half of the part keeps its own
                for fault in ("short", "overtemp", "open_load"):
                    part.inject(fault, k, False)
            return {"ok": 1}
        if op == "regs":  # the bench's logic analyser: what the chip holds now
            part = self.sensed[req["ch"]][0]
            if not hasattr(part, "regs"):
                return {"regs": []}  # a smart switch has no registers
            part.advance(self.world.now_us)
            return {"regs": list(part.regs)}
        if op == "mem":  # with "import": those modules first (their code, not the objects
            import gc  # the firmware makes, is then what a later "mem" counts from)

            for name in req.get("import", ()):
                __import__(name)
            gc.collect()
            return {"alloc": gc.mem_alloc(), "free": gc.mem_free()}  # type: ignore[attr-defined]
        board = self.app.board  # type: ignore[attr-defined]
        return {"r": getattr(board, req["m"])(*req["a"])}

    # --- boots ---------------------------------------------------------------------------

    def boot(self, req: dict) -> "dict | None":  # type: ignore[type-arg]
        """Run boot.py and main.py until the emulator resets the board; its next request."""
        w = self.world
        if self.booted:
            w.reboot()
        self.booted = True
        w.pending = 0
        w.cause = CAUSES.get(req["cause"], _world.PWRON_RESET)
        w.set_time(req["t"] * 1000)
        self.mv = req.get("mv", self.mv)  # the input the board powers up on, as it measures it
        self.reset = False
        asyncio.new_event_loop()  # nothing of the last boot runs
        for name in ("firmware.main", "firmware.boot"):
            sys.modules.pop(name, None)
        self.boot_req = req
        try:
            import firmware.boot

            firmware.boot.run()
            __import__("firmware.main")
            raise OSError("firmware/main.py returned")
        except Unwind as u:
            return u.req
        except _world.BoardReset:
            self.reset = True
            if self.inflight is not None:  # the step it happened in answers it
                self.inflight = None
                self.reset = False
                self.send({"at": w.now_us // 1000 + 1, "feeds": 0, "reboot": True})
        finally:
            self.close_all()
        return self.read_blocking()

    def run(self) -> None:
        req = self.read_blocking()
        while req is not None:
            if req["op"] == "boot":
                req = self.boot(req)
                continue
            if req["op"] == "halt":
                self.send({"ok": 1})
            else:
                self.send(self.answer(req))
            req = self.read_blocking()


def connect(host: str, port: int, name: bytes) -> "socket.socket":
    sock = socket.socket()
    sock.connect(socket.getaddrinfo(host, port)[0][-1])
    sock.write(name + b"\n")  # type: ignore[attr-defined]
    return sock


def main(host: str, port: int, rev: str, tcp: int, modbus: int, tug: int = 0) -> None:
    a = connect(host, port, b"A")
    b = connect(host, port, b"B")
    u = connect(host, port, b"U")
    u.setblocking(False)
    ports = {BOARD_PORTS[0]: tcp, BOARD_PORTS[1]: modbus}
    if tug:
        ports[BOARD_PORTS[2]] = tug
    Bench(rev, a, b, u, ports).run()


if __name__ == "__main__":
    main(sys.argv[1], int(sys.argv[2]), sys.argv[3], int(sys.argv[4]), int(sys.argv[5]),
         int(sys.argv[6]) if len(sys.argv) > 6 else 0)
