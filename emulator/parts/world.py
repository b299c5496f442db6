"""What the microcontroller is wired to: the simulated clock, I2C buses, pins, ADC inputs, the
watchdog and the reset cause; the state behind the ``machine`` module (``emulator.parts.machine``).

A test or the emulator builds a ``World``, wires it (``bus(0).attach(0x40, Ina226(...))``,
``wire_output(pin, fn)``, ``wire_input(pin, fn)``, ``wire_adc(gpio, fn)``), ``install``s it,
and only then lets firmware build ``machine`` objects. Time is ``now_us`` on the simulated
clock: the driver of the simulation moves it (``set_time``), and every bus transaction and ADC
conversion charges its own duration to it (``charge``), as it takes that long on the board.

Resets: a watchdog that is not fed within its timeout, or ``machine.reset()``, makes the next
call into ``machine`` (or the next ``charge``/``set_time``) raise ``BoardReset``, a
``BaseException`` the firmware cannot swallow by ``except Exception``; whoever runs the firmware
catches it, calls ``reboot()`` (every output pin released low, the watchdog stopped, the cause
kept for ``machine.reset_cause()``) and boots the firmware again. The chips on the buses are
powered by the board, not by the microcontroller: they keep their registers across it.
"""

import errno

from emulator.parts.noise import Noise

# machine.reset_cause() values of MicroPython's rp2 port (ports/rp2/modmachine.c)
PWRON_RESET = 1
WDT_RESET = 3

I2C_TIMEOUT_US = 50000  # the rp2 port's default ``timeout`` of machine.I2C
ADC_CONVERSION_US = 2  # RP2040: 96 ADC clocks at 48 MHz
N_GPIO = 30  # GPIO 0-29 (RP2040; the RP2350A's too)


class BoardReset(BaseException):
    """The microcontroller resets now (watchdog or ``machine.reset``); ``cause`` says which."""

    def __init__(self, cause: int) -> None:
        super().__init__(cause)
        self.cause = cause


def _low() -> int:
    return 0


class I2CBus:
    """One I2C bus: the devices on it by 7-bit address. A device has ``acks() -> bool``,
    ``holds_sda() -> bool``, ``i2c_write(data, now_us)`` and ``i2c_read(n, now_us) -> bytes``."""

    def __init__(self, world: "World") -> None:
        self.world = world
        self.devices: dict[int, object] = {}
        self.transactions = 0
        self.busy_us = 0  # time spent on the wire (benchmarks: the tick's bus time)

    def attach(self, addr: int, device: object) -> None:
        self.devices[addr] = device

    def _stuck(self) -> bool:
        return any(dev.holds_sda() for dev in self.devices.values())  # type: ignore[attr-defined]

    def _spend(self, bits: int, freq: int) -> None:
        us = (bits * 1000000 + freq - 1) // freq
        self.busy_us += us
        self.world.charge(us)

    def _address(self, addr: int, freq: int, timeout_us: int) -> object:
        """START and the address byte: the acknowledging device, else OSError."""
        self.transactions += 1
        if self._stuck():
            self.busy_us += timeout_us
            self.world.charge(timeout_us)
            raise OSError(errno.ETIMEDOUT)
        dev = self.devices.get(addr)
        if dev is None or not dev.acks():  # type: ignore[attr-defined]
            self._spend(11, freq)  # START, 8 bits, the missing ACK, STOP
            raise OSError(errno.ENODEV)
        return dev

    def write(self, addr: int, data: bytes, freq: int, timeout_us: int) -> None:
        dev = self._address(addr, freq, timeout_us)
        self._spend(1 + 9 + 9 * len(data) + 1, freq)
        dev.i2c_write(bytes(data), self.world.now_us)  # type: ignore[attr-defined]

    def read(self, addr: int, n: int, freq: int, timeout_us: int) -> bytes:
        dev = self._address(addr, freq, timeout_us)
        self._spend(1 + 9 + 9 * n + 1, freq)
        return dev.i2c_read(n, self.world.now_us)  # type: ignore[attr-defined, no-any-return]

    def read_mem(self, addr: int, reg: int, n: int, freq: int, timeout_us: int) -> bytes:
        """Write the register pointer, repeated START, read ``n`` bytes: one transaction."""
        dev = self._address(addr, freq, timeout_us)
        self._spend(1 + 9 + 9 + 1 + 9 + 9 * n + 1, freq)
        dev.i2c_write(bytes([reg]), self.world.now_us)  # type: ignore[attr-defined]
        return dev.i2c_read(n, self.world.now_us)  # type: ignore[attr-defined, no-any-return]

    def scan(self, freq: int, timeout_us: int) -> "list[int]":
        found = []
        for addr in range(0x08, 0x78):
            try:
                self._address(addr, freq, timeout_us)
            except OSError as exc:
                if exc.args[0] == errno.ETIMEDOUT:
                    raise
                continue
            self._spend(11, freq)
            found.append(addr)
        return found


class World:
    def __init__(self, seed: int = 1, uid: bytes = b"\xe6\x61\x41\x04\x03\x2b\x5a\x2c") -> None:
        self.now_us = 0
        self.noise = Noise(seed)
        self.buses: dict[int, I2CBus] = {}
        self.outputs: dict[int, object] = {}  # pin -> fn(level), the nets an output drives
        self.inputs: dict[int, object] = {}  # pin -> fn() -> level
        self.latches: dict[int, int] = {}  # the output latch of every pin driven
        # the mode and pull of the ``machine.Pin`` last set up on each GPIO (-1: none), for a
        # read of every pad at once (``machine.mem32``); lists made here, so that setting a
        # pin up allocates nothing the firmware's heap figures would count
        self.pad_mode = [-1] * N_GPIO
        self.pad_pull = [-1] * N_GPIO
        self.adcs: dict[int, object] = {}  # GPIO -> fn() -> volts at the pin
        self.vref = 3.3
        self.cause = PWRON_RESET
        self.uid = uid
        self.wdt_timeout_us = 0  # 0: not started
        self.last_feed_us = 0
        self.pending = 0  # a reset cause waiting to be raised
        self.uart_tx: dict[int, bytearray] = {}
        self.uart_rx: dict[int, bytearray] = {}
        self.boots = 1

    # --- wiring ------------------------------------------------------------------------------

    def bus(self, bus_id: int) -> I2CBus:
        if bus_id not in self.buses:
            self.buses[bus_id] = I2CBus(self)
        return self.buses[bus_id]

    def wire_output(self, pin: int, fn: object) -> None:
        self.outputs[pin] = fn

    def wire_input(self, pin: int, fn: object) -> None:
        self.inputs[pin] = fn

    def wire_adc(self, gpio: int, fn: object) -> None:
        self.adcs[gpio] = fn

    # --- time and resets ---------------------------------------------------------------------

    def set_time(self, now_us: int) -> None:
        if now_us > self.now_us:
            self.now_us = now_us
        self.check()

    def charge(self, us: int) -> None:
        """Time the microcontroller spends in a transaction or conversion."""
        self.now_us += us
        self.check()

    def check(self) -> None:
        if not self.pending and self.wdt_timeout_us \
                and self.now_us - self.last_feed_us > self.wdt_timeout_us:
            self.pending = WDT_RESET
        if self.pending:
            raise BoardReset(self.pending)

    def request_reset(self, cause: int) -> None:
        self.pending = cause
        self.check()

    def reboot(self) -> int:
        """The microcontroller comes out of reset: outputs released, watchdog stopped."""
        cause = self.pending or self.cause
        self.pending = 0
        self.cause = cause
        self.wdt_timeout_us = 0
        for pin in list(self.latches):
            self.drive(pin, 0)
        self.latches = {}
        for gpio in range(N_GPIO):  # every pad back to its reset state
            self.pad_mode[gpio] = -1
        self.boots += 1
        return cause

    def drive(self, pin: int, level: int) -> None:
        self.latches[pin] = level
        fn = self.outputs.get(pin)
        if fn is not None:
            fn(level)  # type: ignore[operator]

    def sense(self, pin: int, pull: int) -> int:
        fn = self.inputs.get(pin)
        if fn is not None:
            return 1 if fn() else 0  # type: ignore[operator]
        if pin in self.latches:
            return self.latches[pin]
        return pull

    def adc_volts(self, gpio: int) -> float:
        fn = self.adcs.get(gpio, _low)
        return float(fn())  # type: ignore[operator]


_current: "list[World]" = []


def install(world: World) -> World:
    """Make ``world`` the one ``machine`` objects built from now on are wired to."""
    _current[:] = [world]
    return world


def current() -> World:
    if not _current:
        raise OSError(errno.ENODEV)  # no board: nothing is wired
    return _current[0]
