"""The real board's HAL: ``machine.Pin`` switches, ADC or INA226 current sensing, ``machine.WDT``.

Only ``firmware/main.py`` builds this class (``build``, from a board revision of
``firmware.boards``). Current is read either from one ``machine.ADC`` per channel across a
shunt amplifier (``adc_pins``, ``ma_per_count_x1000`` = mA per ADC count, times 1000) or by a
driver of the revision's sensing parts (``bank``, chosen by ``sense["chip"]`` in ``SENSORS``):
``firmware.hal.ina226.Ina226Bank`` (one INA226 a channel; also built from ``ina226_addrs``
and ``shunt_uohm``), ``firmware.hal.ina3221.Ina3221Bank`` (INA3221, three channels a chip,
its CRITICAL limit a fast trip input, set from ``set_trip_ma``) or
``firmware.hal.profet.ProfetBank`` (smart high-side switches read through the ADC). Each
driver checks its parts at boot and reads ``NO_READING`` (``F_SENSOR``) for a channel whose
part does not answer, ``TRIPPED`` or ``LOW`` where its part says so (``firmware.hal``).
Each switch has an enable pin and, where the board
has one, a status (read-back) pin; without one the enable pin's output latch is read back. On
an RP2040 or RP2350 (``board["mcu"]``, ``GPIO_IN_OF``) the tick reads every switch back at once,
from the SIO's GPIO_IN register (``machine.mem32``: each pin's bit, what its ``Pin.value()``
reads), one call instead of one a pin; elsewhere, and for a pin past GPIO 31, pin by pin.
``ticks_ms`` turns the port's wrapping ``time.ticks_ms`` into a monotonic count with
``ticks_diff``. On the rp2 port ``machine.reset()`` reboots through the watchdog (the next boot
reads ``WDT_RESET``), so ``reboot`` first writes the storage file ``reboot``, and a watchdog
cause with that mark is a soft reset: a reboot the host asked for never counts toward safe mode.
"""

import os
import time as _port_time

import machine  # type: ignore[import-not-found]  # MicroPython only: no stubs

from firmware import boards
from firmware.fast import gpio_read, pins_read
from firmware.hal.ina226 import Ina226Bank
from firmware.hal.ina3221 import Ina3221Bank
from protocol.constants import (
    RESET_BROWNOUT,
    RESET_POWER_ON,
    RESET_SOFT,
    RESET_UNKNOWN,
    RESET_WATCHDOG,
)

if False:  # typing only; MicroPython never imports typing (the block is compiled away)
    from collections.abc import MutableSequence, Sequence
    from typing import Any, Protocol

    from firmware.hal import Storage

    class SenseBank(Protocol):
        """A driver of the sensing parts: ``Ina226Bank``, ``Ina3221Bank``, ``ProfetBank``."""

        def setup(self) -> None: ...

        def report(self) -> "list[str]": ...

        def read_one(self, ch: int) -> int: ...

        def read(self, out: "MutableSequence[int]") -> None: ...

    class Adc(Protocol):
        """A ``machine.ADC``."""

        def read_u16(self) -> int: ...

    class MpTime(Protocol):
        """What the HAL uses of MicroPython's ``time`` (CPython's has none of it)."""

        def ticks_ms(self) -> int: ...

        def ticks_diff(self, a: int, b: int) -> int: ...

        def sleep_us(self, us: int) -> None: ...

# the port's ``time`` as the HAL sees it (the part tests hand it emulator.parts.boardtime's)
time: "MpTime" = _port_time  # type: ignore[assignment]  # MicroPython's, beyond CPython's

REBOOT_MARK = "reboot"  # a reboot this firmware asked for (storage file)
# the MCUs whose SIO has GPIO_IN (every GPIO's input level, bit n GPIO n, n < 32) and its
# address: RP2040 datasheet 2.3.1.7, RP2350 datasheet 3.1.11 (SIO_BASE 0xd0000000 + 0x004)
GPIO_IN_OF = {"rp2040": 0xD0000004, "rp2350": 0xD0000004}


class TargetHal:
    def __init__(self, en_pins: "Sequence[int]", status_pins: "Sequence[int] | None" = None,
                 adc_pins: "Sequence[int] | None" = None, ma_per_count_x1000: int = 1000,
                 i2c: "Any" = None, ina226_addrs: "tuple[int, ...] | None" = None,
                 shunt_uohm: int = 10000, vin_adc_pin: "int | None" = None,
                 mv_per_count_x1000: int = 1000, wdt_timeout_ms: int = 2000,
                 storage: "Storage | None" = None, bank: "SenseBank | None" = None,
                 gpio_in: "int | None" = None) -> None:
        self.n_channels = len(en_pins)
        self.en = [machine.Pin(p, machine.Pin.OUT, value=0) for p in en_pins]
        self.status = [machine.Pin(p, machine.Pin.IN) for p in status_pins] if status_pins else None
        # the switches read back (status pins, else the enables): by GPIO_IN at ``gpio_in``
        # when the MCU has one (an address of GPIO_IN_OF) and every pin is in it, else a pin
        # at a time
        back = status_pins if status_pins else en_pins
        in_word = all(isinstance(p, int) and 0 <= p < 32 for p in back)
        self.gpio_in = gpio_in if in_word else None
        self.mem32 = machine.mem32 if self.gpio_in is not None else None
        self.back_bits = bytes(back) if in_word else b""  # each switch's bit in GPIO_IN
        self.adc: "list[Adc] | None" = \
            [machine.ADC(machine.Pin(p)) for p in adc_pins] if adc_pins else None
        self.ma_k = ma_per_count_x1000
        if bank is None and ina226_addrs:
            bank = Ina226Bank(i2c, ina226_addrs, shunt_uohm)
        self.ina = bank  # the sensing chips' driver (INA226, INA3221 or smart switches)
        if bank is not None and hasattr(bank, "wire"):  # a smart switch's driver reads its
            # inputs' levels: in one word of GPIO_IN when every enable is a bit of it
            en_word = gpio_in is not None and all(isinstance(p, int) and 0 <= p < 32
                                                  for p in en_pins)
            bank.wire(self.en, (machine.mem32, gpio_in, bytes(en_pins)) if en_word else None)
        if self.ina is not None:
            self.ina.setup()
            # the tick's read goes straight to the driver: an instance attribute over the
            # method, one Python call a tick fewer (setattr: a method is not assigned to)
            setattr(self, "read_currents_ma", self.ina.read)  # noqa: B010
        self.vin: "Adc | None" = \
            machine.ADC(machine.Pin(vin_adc_pin)) if vin_adc_pin is not None else None
        self.mv_k = mv_per_count_x1000
        self._t0 = time.ticks_ms()
        self._ms = 0
        # None only for a HAL no Board runs on (the part tests); build() always gives one
        self.storage: "Storage" = storage  # type: ignore[assignment]  # (see above)
        self._cause = self._read_cause()
        self.wdt = machine.WDT(timeout=wdt_timeout_ms)
        # the main loop's feed goes straight to the watchdog's (as read_currents_ma above)
        setattr(self, "wdt_feed", self.wdt.feed)  # noqa: B010
        # the input ADC's read, bound once (the tick reads it every time)
        self.vin_read = self.vin.read_u16 if self.vin is not None else None

    def _read_cause(self) -> int:
        c = machine.reset_cause()
        asked = False  # rp2: machine.reset() reboots by the watchdog; reboot() left a mark
        st = self.storage
        if st is not None and st.read(REBOOT_MARK) is not None:
            asked = True
            st.remove(REBOOT_MARK)
        if c == getattr(machine, "WDT_RESET", -1):
            return RESET_SOFT if asked else RESET_WATCHDOG
        if c == getattr(machine, "SOFT_RESET", -1):
            return RESET_SOFT
        if c == getattr(machine, "PWRON_RESET", -1):
            return RESET_POWER_ON
        if c == getattr(machine, "BROWNOUT_RESET", -2):
            return RESET_BROWNOUT
        return RESET_UNKNOWN

    def report(self) -> "list[str]":
        """What the board prints at boot about its current sensors, one line each."""
        return self.ina.report() if self.ina is not None else []

    def ticks_ms(self) -> int:
        t = time.ticks_ms()
        self._ms += time.ticks_diff(t, self._t0)
        self._t0 = t
        return self._ms

    def read_current_ma(self, ch: int) -> int:
        if self.ina is not None:
            return self.ina.read_one(ch)
        if self.adc is not None:
            return self.adc[ch].read_u16() * self.ma_k // 1000
        return 0

    def read_currents_ma(self, out: "MutableSequence[int]") -> None:
        if self.ina is not None:
            self.ina.read(out)
            return
        for ch in range(self.n_channels):
            out[ch] = self.read_current_ma(ch)

    def set_trip_ma(self, ch: int, ma: int) -> None:
        setter = getattr(self.ina, "set_trip_ma", None)
        if setter is not None:
            setter(ch, ma)

    def set_switch(self, ch: int, on: bool) -> None:
        self.en[ch].value(1 if on else 0)

    def read_switch(self, ch: int) -> bool:
        if self.status is not None:
            return bool(self.status[ch].value())
        return bool(self.en[ch].value())

    def read_switches(self, out: "Any") -> None:
        """Every switch read back into ``out`` (array('i')): 1 or 0, as ``read_switch``."""
        if self.gpio_in is not None:
            gpio_read(self.mem32, self.gpio_in, self.back_bits, out, self.n_channels)
        else:
            pins_read(self.status if self.status is not None else self.en, out, self.n_channels)

    def read_input_mv(self) -> int:
        read = self.vin_read
        return read() * self.mv_k // 1000 if read is not None else 0

    def wdt_feed(self) -> None:
        self.wdt.feed()

    def reset_cause(self) -> int:
        return self._cause

    def random_bytes(self, n: int) -> bytes:
        return os.urandom(n)

    def reboot(self) -> None:
        if self.storage is not None:  # read back at the next boot: RESET_SOFT, not watchdog
            self.storage.write(REBOOT_MARK, b"1")
        machine.reset()


def _i2c(sense: "dict[str, Any]") -> "Any":  # a machine.I2C
    bus = sense["i2c"]
    return machine.I2C(bus["id"], scl=machine.Pin(bus["scl"]), sda=machine.Pin(bus["sda"]),
                       freq=bus["freq"], timeout=bus["timeout_us"])


def _ina226(sense: "dict[str, Any]") -> "SenseBank":
    return Ina226Bank(_i2c(sense), sense["addrs"], sense["shunt_uohm"])


def _ina3221(sense: "dict[str, Any]") -> "SenseBank":
    return Ina3221Bank(_i2c(sense), sense["addrs"], sense["inputs"], sense["shunt_uohm"])


def _profet(sense: "dict[str, Any]") -> "SenseBank":
    from firmware.hal.profet import ProfetBank

    return ProfetBank(sense, machine, time.sleep_us)


SENSORS = {"ina226": _ina226, "ina3221": _ina3221, "profet": _profet}


def build(board: "dict[str, Any]", storage: "Storage") -> TargetHal:
    """The HAL of a board revision's description (``firmware.boards``): its sensing chips (by
    ``sense["chip"]``, one of ``SENSORS``), its pins and its input divider, as
    ``firmware/main.py`` boots it."""
    sense = board["sense"]
    bank = SENSORS[sense["chip"]](sense)
    vin = board["vin"]
    return TargetHal(board["en_pins"], board["status_pins"] or None, bank=bank,
                     vin_adc_pin=vin["adc_pin"],
                     mv_per_count_x1000=boards.mv_per_count_x1000(vin), storage=storage,
                     gpio_in=GPIO_IN_OF.get(board["mcu"]))
