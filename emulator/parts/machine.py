"""The ``machine`` module of MicroPython's rp2 port (Raspberry Pi Pico / RP2040), over a ``World``.

Put ``emulator/parts`` on ``MICROPYPATH`` (MicroPython >= 1.21 lets a file on the path stand in
for a built-in module) and the firmware's ``import machine`` gets this: the same classes and
calls as on the board, wired to the simulated parts of ``emulator.parts.world.current()``.

- ``Pin(id, mode, pull, value=)``: ``IN``/``OUT``/``OPEN_DRAIN``, ``PULL_UP``/``PULL_DOWN``;
  ``value()``, ``on``/``off``/``toggle``, calling it. An output drives the net the world wired
  to it (a switch's enable); an input reads the net wired to it (a switch's status output),
  else its pull.
- ``I2C(id, scl=, sda=, freq=400000, timeout=50000)``: ``scan``, ``readfrom_mem_into``,
  ``readfrom_mem``, ``writeto_mem``, ``readfrom``, ``readfrom_into``, ``writeto``. An absent or
  NACKing address raises ``OSError(ENODEV)``, a bus held low ``OSError(ETIMEDOUT)`` after the
  timeout; every transaction charges its bits at ``freq`` (9 per byte, plus START/STOP) to the
  simulated clock.
- ``ADC(pin or channel)``: ``read_u16`` is the RP2040's 12-bit conversion of the pin's voltage
  against 3.3 V, with the noise of its ENOB of about 8.7 bits (2.84 LSB rms), scaled to 16 bit
  as the port does (``raw << 4 | raw >> 8``).
- ``mem32[SIO_GPIO_IN]`` (0xd0000004, RP2040 datasheet 2.3.1.7; the same on the RP2350): every
  GPIO's level in one word, bit n GPIO n, each read as its ``Pin.value()`` would (an output:
  its latch; an input or open drain: its net, else its pull; a GPIO never set up: its net,
  else 0). Any other address, and any write, raises ``ValueError``: nothing else of the chip's
  memory is modelled, and firmware must not read something made up.
- ``WDT(timeout=ms)``: ``feed``; unfed for longer than the timeout, the board resets (the next
  call into ``machine`` raises ``BoardReset``); at most 8388 ms, as on the RP2040.
- ``UART(id, baudrate)``: ``write``, ``read``, ``readinto``, ``readline``, ``any``; bytes go to
  and come from the world's ``uart_tx``/``uart_rx``.
- ``reset()`` (on rp2 it goes through the watchdog: the next boot reads ``WDT_RESET``),
  ``reset_cause()`` (``PWRON_RESET`` 1, ``WDT_RESET`` 3), ``unique_id()`` (8 bytes, the flash's
  id), ``freq()``, ``idle()``, ``disable_irq``/``enable_irq``.
"""

from emulator.parts import world as _world
from emulator.parts.world import PWRON_RESET, WDT_RESET, BoardReset

__all__ = [
    "ADC",
    "I2C",
    "PWRON_RESET",
    "SIO_GPIO_IN",
    "UART",
    "WDT",
    "WDT_RESET",
    "BoardReset",
    "Pin",
    "disable_irq",
    "enable_irq",
    "freq",
    "idle",
    "mem32",
    "reset",
    "reset_cause",
    "unique_id",
]

ADC_NOISE_LSB = 2.84  # 2 ** (12 - 8.7) / sqrt(12): the RP2040's ENOB of about 8.7 bits
WDT_MAX_MS = 8388
SIO_GPIO_IN = 0xD0000004  # the SIO's GPIO_IN register (RP2040 and RP2350)


def _w() -> "_world.World":
    w = _world.current()
    w.check()
    return w


def _pin_id(pin: object) -> int:
    if isinstance(pin, Pin):
        return pin.id
    return int(pin)  # type: ignore[call-overload, no-any-return]


class Pin:
    IN = 0
    OUT = 1
    OPEN_DRAIN = 2
    ALT = 3
    PULL_UP = 1
    PULL_DOWN = 2

    def __init__(self, id: object, mode: int = -1, pull: int = -1,
                 value: "int | None" = None) -> None:
        self.id = _pin_id(id)
        if not 0 <= self.id <= 29:
            raise ValueError("invalid pin")
        self.mode = self.IN if mode == -1 else mode
        self.pull = pull
        w = _w()
        w.pad_mode[self.id] = self.mode
        w.pad_pull[self.id] = pull
        if value is not None:
            w.latches[self.id] = 1 if value else 0
        if self.mode == self.OUT:
            w.drive(self.id, w.latches.get(self.id, 0))

    def init(self, mode: int = -1, pull: int = -1, value: "int | None" = None) -> None:
        self.__init__(self.id, mode, pull, value)  # type: ignore[misc]

    def value(self, x: "int | None" = None) -> "int | None":
        w = _w()
        if x is None:
            return _level(w, self.id, self.mode, self.pull)
        level = 1 if x else 0
        if self.mode == self.OUT:
            w.drive(self.id, level)
        else:
            w.latches[self.id] = level  # the output latch, driven once the pin is an output
        return None

    def __call__(self, x: "int | None" = None) -> "int | None":
        return self.value(x)

    def on(self) -> None:
        self.value(1)

    def off(self) -> None:
        self.value(0)

    def toggle(self) -> None:
        self.value(0 if self.value() else 1)


def _level(w: "_world.World", gpio: int, mode: int, pull: int) -> int:
    """What a GPIO set up as ``mode`` with ``pull`` reads: an output its latch, else its net
    (its pull if nothing is wired to it)."""
    if mode == Pin.OUT:
        return w.latches.get(gpio, 0)
    return w.sense(gpio, 1 if pull == Pin.PULL_UP else 0)


class _Mem32:
    """``machine.mem32``: of the chip's memory only the SIO's GPIO_IN register is modelled."""

    def __getitem__(self, addr: int) -> int:
        w = _w()
        if addr != SIO_GPIO_IN:
            raise ValueError(f"mem32[0x{addr:x}]: not modelled (only SIO GPIO_IN,"
                             f" 0x{SIO_GPIO_IN:x})")
        word = 0
        for gpio in range(_world.N_GPIO):
            mode = w.pad_mode[gpio]
            # a GPIO never set up: its pad's reset state, an input (its net, else 0)
            if _level(w, gpio, mode, w.pad_pull[gpio]) if mode >= 0 else w.sense(gpio, 0):
                word |= 1 << gpio
        return word

    def __setitem__(self, addr: int, value: int) -> None:
        raise ValueError(f"mem32[0x{addr:x}] = {value}: writes are not modelled")


mem32 = _Mem32()


class I2C:
    def __init__(self, id: int = 0, scl: object = None, sda: object = None,
                 freq: int = 400000, timeout: int = _world.I2C_TIMEOUT_US) -> None:
        if id not in (0, 1):
            raise ValueError(f"I2C({id}) doesn't exist")
        self.id = id
        self.freq = freq
        self.timeout = timeout
        self.bus = _w().bus(id)

    def scan(self) -> "list[int]":
        _w()
        return self.bus.scan(self.freq, self.timeout)

    def writeto(self, addr: int, buf: bytes, stop: bool = True) -> int:
        _w()
        self.bus.write(addr, bytes(buf), self.freq, self.timeout)
        return len(buf)

    def readfrom(self, addr: int, nbytes: int, stop: bool = True) -> bytes:
        _w()
        return self.bus.read(addr, nbytes, self.freq, self.timeout)

    def readfrom_into(self, addr: int, buf: bytearray, stop: bool = True) -> None:
        got = self.readfrom(addr, len(buf))
        for i in range(len(buf)):
            buf[i] = got[i]

    def writeto_mem(self, addr: int, memaddr: int, buf: bytes, addrsize: int = 8) -> None:
        _w()
        self.bus.write(addr, bytes([memaddr]) + bytes(buf), self.freq, self.timeout)

    def readfrom_mem(self, addr: int, memaddr: int, nbytes: int, addrsize: int = 8) -> bytes:
        _w()
        return self.bus.read_mem(addr, memaddr, nbytes, self.freq, self.timeout)

    def readfrom_mem_into(self, addr: int, memaddr: int, buf: bytearray,
                          addrsize: int = 8) -> None:
        got = self.readfrom_mem(addr, memaddr, len(buf))
        for i in range(len(buf)):
            buf[i] = got[i]


class ADC:
    CORE_TEMP = 4

    def __init__(self, pin: object) -> None:
        if isinstance(pin, Pin):
            gpio = pin.id
        else:
            ch = int(pin)  # type: ignore[call-overload]
            gpio = ch + 26 if 0 <= ch <= 4 else ch
        if not 26 <= gpio <= 30:
            raise ValueError("Pin doesn't have ADC capabilities")
        self.gpio = gpio
        _w()

    def read_u16(self) -> int:
        w = _w()
        w.charge(_world.ADC_CONVERSION_US)
        v = w.adc_volts(self.gpio)
        raw = round(v / w.vref * 4095 + w.noise.gauss(ADC_NOISE_LSB))
        raw = 0 if raw < 0 else 4095 if raw > 4095 else raw
        return (raw << 4) | (raw >> 8)


class WDT:
    def __init__(self, id: int = 0, timeout: int = 5000) -> None:
        if timeout > WDT_MAX_MS:
            raise ValueError("timeout exceeds " + str(WDT_MAX_MS))
        w = _w()
        w.wdt_timeout_us = timeout * 1000
        w.last_feed_us = w.now_us

    def feed(self) -> None:
        w = _w()
        w.last_feed_us = w.now_us


class UART:
    def __init__(self, id: int, baudrate: int = 115200, **kw: object) -> None:
        self.id = id
        self.baudrate = baudrate
        w = _w()
        self.tx = w.uart_tx.setdefault(id, bytearray())
        self.rx = w.uart_rx.setdefault(id, bytearray())

    def any(self) -> int:
        return len(self.rx)

    def write(self, buf: bytes) -> int:
        w = _w()
        self.tx.extend(buf)
        w.charge(len(buf) * 10 * 1000000 // self.baudrate)
        return len(buf)

    def read(self, n: int = -1) -> "bytes | None":
        if not self.rx:
            return None
        n = len(self.rx) if n < 0 else min(n, len(self.rx))
        out = bytes(self.rx[:n])
        self.rx[:] = self.rx[n:]
        return out

    def readinto(self, buf: bytearray) -> "int | None":
        got = self.read(len(buf))
        if got is None:
            return None
        for i in range(len(got)):
            buf[i] = got[i]
        return len(got)

    def readline(self) -> "bytes | None":
        i = self.rx.find(b"\n")
        return self.read(-1 if i < 0 else i + 1)


def reset() -> None:
    _world.current().request_reset(WDT_RESET)  # rp2: machine.reset() reboots by the watchdog


def reset_cause() -> int:
    return _w().cause


def unique_id() -> bytes:
    return _w().uid


def freq() -> int:
    return 125000000


def idle() -> None:
    _w()


def disable_irq() -> int:
    return 0


def enable_irq(state: int = 0) -> None:
    pass

