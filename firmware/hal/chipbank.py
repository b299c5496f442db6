"""The current-monitor chips of a board revision on one I2C bus, driven so that the board can
trust them: what the INA226 and the INA3221 drivers share.

A ``ChipBank`` owns ``chips`` (their 7-bit addresses) and maps each switched channel to a chip
and an input of it (``chip_of[ch]``, ``input_of[ch]``). ``setup()`` at boot checks each chip's
manufacturer (FE = 0x5449) and die (FF) IDs and configures it; ``read(out)`` fills one value per
channel: the current in mA, or a code of ``firmware.hal`` (``NO_READING`` when the chip gives
none: the channel then raises ``F_SENSOR``, see ``firmware/channel.py``; ``TRIPPED`` when the
chip's own per-conversion limit fired). A subclass names its IDs and configuration
(``_write_config``), how it reads a channel (``_sample``) and what it checks once per tick
(``_before``).

Trust: a chip that does not answer (``OSError`` ENODEV, a NACK) reads ``NO_READING`` and is
configured again when it answers; a bus held low (``ETIMEDOUT``) reads ``NO_READING`` on every
channel and is tried again every ``BUS_RETRY_TICKS`` reads (a stuck bus costs the I2C timeout
each try); a chip with the wrong IDs (another part at the address) reads ``NO_READING`` until
the next boot. Every read checks one chip's CONFIG in turn; a chip found with another CONFIG
than the one written (a brown-out of the chip: back at power-on) is configured again
(``resets``).
"""

import errno
from array import array

from firmware.hal import NO_READING
from protocol.compat import const

if False:  # typing only; MicroPython never imports typing (the block is compiled away)
    from collections.abc import MutableSequence
    from typing import Protocol

    class I2c(Protocol):
        """A ``machine.I2C`` (or the emulator's bus): the two memory transfers the drivers use."""

        def readfrom_mem_into(self, addr: int, memaddr: int, buf: bytearray) -> None: ...

        def writeto_mem(self, addr: int, memaddr: int, buf: bytearray) -> None: ...

REG_CONFIG = const(0x00)
REG_MANUFACTURER = const(0xFE)
REG_DIE = const(0xFF)
MANUFACTURER = const(0x5449)
BUS_RETRY_TICKS = const(10)

# per chip (``state``, a byte each: the viper reads index it as one)
C_UNKNOWN = const(0)  # not configured (boot, or it stopped answering)
C_OK = const(1)
C_WRONG = const(2)  # another chip at the address: never trusted

# ``prog`` (array('i')): what the drivers' viper reads (firmware.fast) share with the bank
P_AT = const(0)  # the channel being read; n + chip while checking that chip's CONFIG
P_PART = const(1)  # INA3221: 0 while at its chip's MASK/ENABLE, 1 while at its SHUNT
P_TRIPS = const(2)  # INA3221: fast trips counted
P_CHECK = const(3)  # the chip whose CONFIG the next read checks
P_CHIPS = const(4)  # how many chips
P_RESET = const(5)  # after a checking read: the chip found back at power-on + 1, or 0


class ChipBank:
    NAME = "chip"
    DIE = 0
    CONFIG_TICK = 0
    BEFORE = False  # True when _before does something (the read then calls it every tick)

    def __init__(self, i2c: "I2c", chips: "tuple[int, ...]", chip_of: "list[int]",
                 input_of: "list[int]") -> None:
        self.i2c = i2c
        self.chips = chips
        self.n_chips = len(chips)
        self.chip_of = chip_of
        self.input_of = input_of
        self.n = len(chip_of)
        # the bus's read, bound once (a bound method looked up at each use is made anew)
        self.rd = i2c.readfrom_mem_into
        self.state = bytearray(self.n_chips)  # C_UNKNOWN each
        self.ids = [0] * self.n_chips  # (manufacturer << 16) | die, as last read
        # the CONFIG each chip is written and checked against (a subclass whose chips differ
        # sets its own)
        self.configs = array("i", [self.CONFIG_TICK] * self.n_chips)
        self.buf = bytearray(2)
        self.wbuf = bytearray(2)
        self.prog = array("i", [0, 0, 0, 0, self.n_chips, 0])  # P_AT ... P_RESET
        self.bus_wait = 0  # reads left before a bus that timed out is tried again
        self.resets = 0  # chips found back at power-on and configured again
        self.errors = 0  # transactions that failed

    def _get(self, chip: int, reg: int) -> int:
        self.rd(self.chips[chip], reg, self.buf)
        return (self.buf[0] << 8) | self.buf[1]

    def _put(self, chip: int, reg: int, value: int) -> None:
        self.wbuf[0] = (value >> 8) & 0xFF
        self.wbuf[1] = value & 0xFF
        self.i2c.writeto_mem(self.chips[chip], reg, self.wbuf)

    def _write_config(self, chip: int) -> None:
        raise NotImplementedError

    def _sample(self, ch: int) -> int:
        """One channel's value (mA or a code); ``OSError`` if the chip does not answer."""
        raise NotImplementedError

    def _before(self, chip: int) -> None:
        """Once per read, before the chip's channels are sampled (flags to fetch)."""

    def _configure(self, chip: int) -> None:
        """Check the IDs and configure one chip; ``OSError`` if it does not answer."""
        self.ids[chip] = (self._get(chip, REG_MANUFACTURER) << 16) | self._get(chip, REG_DIE)
        if self.ids[chip] != (MANUFACTURER << 16) | self.DIE:
            self.state[chip] = C_WRONG
            return
        self._write_config(chip)
        self.state[chip] = C_OK

    def _failed(self, chip: int, exc: OSError) -> bool:
        """A transaction failed: True when the whole bus is down (held low)."""
        self.errors += 1
        if self.state[chip] == C_OK:
            self.state[chip] = C_UNKNOWN
        if exc.args and exc.args[0] == errno.ETIMEDOUT:
            self.bus_wait = BUS_RETRY_TICKS
            return True
        return False

    def setup(self) -> None:
        """At boot: every chip's IDs checked and configured (those that answer)."""
        for chip in range(self.n_chips):
            try:
                self._configure(chip)
            except OSError as exc:
                if self._failed(chip, exc):
                    return

    def report(self) -> "list[str]":
        """One line per channel, as the board prints them at boot: ``ch0 0x40 ina226 ok``,
        ``ch1 0x41 no answer``, ``ch2 0x42 wrong chip 5449:3220``, ``ch3 0x43 bus held low``
        (a chip with several inputs adds its input: ``ch4 0x41.1 ina3221 ok``)."""
        out = []
        for ch in range(self.n):
            chip = self.chip_of[ch]
            st = self.state[chip]
            if st == C_OK:
                what = self.NAME + " ok"
            elif st == C_WRONG:
                i = self.ids[chip]
                what = "wrong chip %04x:%04x" % (i >> 16, i & 0xFFFF)
            elif self.bus_wait:
                what = "bus held low"
            else:
                what = "no answer"
            where = "0x%02x" % self.chips[chip]
            if self.n != self.n_chips:
                where += ".%d" % self.input_of[ch]
            out.append("ch%d %s %s" % (ch, where, what))
        return out

    def _ready(self, chip: int) -> bool:
        """The chip may be read now (configured first if it was not); ``OSError`` passes."""
        st = self.state[chip]
        if st == C_WRONG or self.bus_wait:
            return False
        if st == C_UNKNOWN:
            self._configure(chip)
        return self.state[chip] == C_OK

    def read_one(self, ch: int) -> int:
        """One channel's current in mA (>= 0), or a code: ``NO_READING``, ``TRIPPED``."""
        chip = self.chip_of[ch]
        try:
            if not self._ready(chip):
                return NO_READING
            return self._sample(ch)
        except OSError as exc:
            self._failed(chip, exc)
            return NO_READING

    def read(self, out: "MutableSequence[int]") -> None:
        """Every channel's value into ``out``; then one chip's configuration checked."""
        if self.bus_wait:
            self.bus_wait -= 1
            for ch in range(self.n):
                out[ch] = NO_READING
            return
        last = -1
        chip_of, state, sample = self.chip_of, self.state, self._sample
        before = self.BEFORE
        for ch in range(self.n):
            chip = chip_of[ch]
            # a new chip: made ready and its flags fetched, unless it is ready already and has
            # no flags (then _ready would return True doing nothing, and _before nothing)
            if chip != last and (before or state[chip] != C_OK or self.bus_wait):
                try:
                    if self._ready(chip):
                        self._before(chip)
                except OSError as exc:
                    self._failed(chip, exc)
            last = chip
            if state[chip] == C_OK and not self.bus_wait:  # read_one's path for a ready chip
                try:
                    out[ch] = sample(ch)
                except OSError as exc:
                    self._failed(chip, exc)
                    out[ch] = NO_READING
            else:
                out[ch] = self.read_one(ch)
        self._check()

    def _read_channel(self, out: "MutableSequence[int]", ch: int, new_chip: bool) -> None:
        """``read``'s body for channel ``ch`` alone: its chip made ready and its flags fetched
        first when ``new_chip``, then the channel sampled (``read_one`` if the chip is not
        ready). The drivers' fast reads hand a channel here when their loop cannot take it."""
        chip = self.chip_of[ch]
        if new_chip:
            try:
                if self._ready(chip):
                    self._before(chip)
            except OSError as exc:
                self._failed(chip, exc)
        if self.state[chip] == C_OK and not self.bus_wait:
            try:
                out[ch] = self._sample(ch)
            except OSError as exc:
                self._failed(chip, exc)
                out[ch] = NO_READING
        else:
            out[ch] = self.read_one(ch)

    def _check(self) -> None:
        """One chip's CONFIG checked, the chips in turn (``prog[P_CHECK]``); the drivers' viper
        reads do the same at the end of a read that took every channel."""
        prog = self.prog
        chip = prog[P_CHECK]
        prog[P_CHECK] = chip + 1 if chip + 1 < self.n_chips else 0
        if self.state[chip] != C_OK or self.bus_wait:
            return
        buf = self.buf  # _get inlined: this runs every tick
        try:
            self.rd(self.chips[chip], REG_CONFIG, buf)
            if (buf[0] << 8) | buf[1] != self.configs[chip]:
                self._reset_found(chip)
        except OSError as exc:
            self._failed(chip, exc)

    def _reset_found(self, chip: int) -> None:
        """The check found ``chip``'s CONFIG back at power-on (or changed): configure it again
        (``OSError`` passes)."""
        self.resets += 1
        self._configure(chip)

    def _checked(self, exc: "OSError | None") -> None:
        """After a viper read that checked a chip's CONFIG (``prog[P_AT]``: n + chip):
        ``exc`` its transaction's error, else ``prog[P_RESET]`` says whether it reset."""
        prog = self.prog
        if exc is not None:
            self._failed(prog[P_AT] - self.n, exc)
            return
        chip = prog[P_RESET] - 1
        try:
            self._reset_found(chip)
        except OSError as err:
            self._failed(chip, err)
