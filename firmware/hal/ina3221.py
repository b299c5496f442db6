"""The INA3221 triple shunt monitors of a board revision (TI SBOS576): up to three channels a
chip, with a per-conversion CRITICAL limit used as a fast trip input.

``Ina3221Bank`` is a ``firmware.hal.chipbank.ChipBank`` (IDs 5449:3220 checked at boot, a
chip that does not answer or a bus held low read as ``NO_READING``, a chip that reset
configured again): ``chips`` the addresses (A0 to GND, VS, SDA, SCL: 0x40-0x43), ``inputs``
one ``(chip index, input 0-2)`` per channel.

Configuration for the 10 ms protection tick (CONFIG): the used inputs enabled, AVG = 4,
VBUSCT = 140 us, VSHCT = 588 us, shunt and bus continuous (0x721F with all three inputs). One
result of every enabled input every sum over enabled inputs of (VBUSCT + VSHCT) x AVG = 3 x
(140 + 588) x 4 = 8,736 us (2 inputs: 5,824 us), less than the 10 ms tick: every tick reads a
result at most 8.7 ms old, averaged over 4 shunt conversions of 588 us each. The shunt register
is 40 uV/LSB (left-aligned by 3): over a 10 mOhm shunt, 4 mA a count up to 16.38 A.

The fast trip: each input's CRITICAL limit (07/09/0B) is set to its channel's instant-trip
current (``set_trip_ma``, from the channel's configuration: rated x trip factor) and compared
by the chip with *every* shunt conversion, not the average; CEN latches the flags CF1-3 until
MASK/ENABLE is read. Every tick reads MASK/ENABLE once a chip (before its inputs): a channel
whose CF is set reads ``TRIPPED`` (the channel trips at once) instead of its averaged current.
Bus time a tick at 400 kHz (120 us a register read): 10 inputs + 4 MASK/ENABLE + 1 CONFIG
check = 15 reads, 1.8 ms. A chip that reset (CONFIG back at 0x7127, limits at 0x7FF8, CEN 0) is
configured again, limits included.
"""

from array import array

from firmware.fast import ina3221_read
from firmware.hal import NO_READING, TRIPPED
from firmware.hal.chipbank import P_AT, P_PART, P_RESET, P_TRIPS, ChipBank
from protocol.compat import const

if False:  # typing only (compiled away on the board)
    from collections.abc import MutableSequence
    from typing import Any

    from firmware.hal.chipbank import I2c

REG_CONFIG = const(0x00)
REG_MASK = const(0x0F)
CEN = const(0x0400)
CF1 = const(0x0200)
CONFIG_BASE = 0x021F  # AVG 4, VBUSCT 140 us, VSHCT 588 us, shunt and bus continuous
NO_LIMIT = 0x7FF8  # the power-on CRITICAL limit: +163.8 mV


def config_for(inputs: int) -> int:
    """CONFIG with the inputs of bit mask ``inputs`` (bit 0 = input 1) enabled."""
    en = ((inputs & 1) << 2) | (inputs & 2) | ((inputs & 4) >> 2)
    return (en << 12) | CONFIG_BASE


def limit_code(trip_ma: int, shunt_uohm: int) -> int:
    """The CRITICAL register for a trip current: mA x uOhm = nV, 40,000 nV a count, left-aligned
    by 3, at most the full scale."""
    code = trip_ma * shunt_uohm // 40000
    return NO_LIMIT if code >= 4095 else code << 3


class Ina3221Bank(ChipBank):
    NAME = "ina3221"
    DIE = 0x3220
    BEFORE = True  # MASK/ENABLE read once a chip, before its inputs

    def __init__(self, i2c: "I2c", chips: "tuple[int, ...]",
                 inputs: "tuple[tuple[int, int], ...]", shunt_uohm: int) -> None:
        super().__init__(i2c, chips, [c for c, _ in inputs], [k for _, k in inputs])
        self.shunt_uohm = shunt_uohm
        used = [0] * len(chips)
        for c, k in inputs:
            used[c] |= 1 << k
        self.configs = array("i", [config_for(u) for u in used])
        self.limits = [NO_LIMIT] * self.n  # CRITICAL register per channel
        self.flags = array("i", [0] * len(chips))  # MASK/ENABLE as read this tick
        self.trips = 0  # fast trips seen (a CRITICAL flag)
        # for the viper read: a byte per chip, two per channel (and ChipBank.prog)
        self.addr_b = bytes(chips)
        self.chip_b = bytes(self.chip_of)
        self.input_b = bytes(self.input_of)

    def _write_config(self, chip: int) -> None:
        self._put(chip, REG_CONFIG, self.configs[chip])
        for ch in range(self.n):
            if self.chip_of[ch] == chip:
                self._put(chip, 7 + 2 * self.input_of[ch], self.limits[ch])
        self._put(chip, REG_MASK, CEN)
        self.flags[chip] = 0

    def set_trip_ma(self, ch: int, ma: int) -> None:
        """The channel's instant-trip current as its input's CRITICAL limit."""
        code = limit_code(ma, self.shunt_uohm)
        if code == self.limits[ch]:
            return
        self.limits[ch] = code
        chip = self.chip_of[ch]
        try:
            if self._ready(chip):
                self._put(chip, 7 + 2 * self.input_of[ch], code)
        except OSError as exc:
            self._failed(chip, exc)

    def read(self, out: "MutableSequence[int]") -> None:
        """As ``ChipBank.read``, each run of channels whose chips are ready read by
        ``firmware.fast.ina3221_read`` (MASK/ENABLE at each new chip, then its inputs); an
        ``OSError`` there handled as ``ChipBank.read`` does for ``_before`` or ``_sample``, at
        the same channel; a chip not ready read by ``ChipBank.read``'s body."""
        if self.bus_wait:
            ChipBank.read(self, out)
            return
        n = self.n
        prog = self.prog
        ch = 0
        while ch < n:
            before = True
            if not self.bus_wait:
                try:
                    ch = ina3221_read(self.rd, self.addr_b, self.chip_b, self.input_b,
                                      self.state, self.flags, self.buf, out, ch, n,
                                      self.shunt_uohm, prog, self.configs)
                except OSError as exc:
                    ch = prog[P_AT]
                    if ch >= n:  # the CONFIG check's read, after every channel
                        if prog[P_TRIPS]:
                            self._tripped(prog)
                        self._checked(exc)
                        return
                    self._failed(self.chip_of[ch], exc)
                    if prog[P_PART]:  # its SHUNT (_sample's)
                        out[ch] = NO_READING
                        ch += 1
                        continue
                    before = False  # its chip's MASK/ENABLE (_before's): on with the channel
                if ch > n:  # every channel read and a CONFIG checked
                    if prog[P_TRIPS]:
                        self._tripped(prog)
                    if prog[P_RESET]:
                        self._checked(None)
                    return
            self._one(out, ch, before)
            ch += 1
        if prog[P_TRIPS]:
            self._tripped(prog)
        self._check()

    def _tripped(self, prog: "Any") -> None:
        """The fast trips the viper read counted (``prog[P_TRIPS]``) into ``trips``."""
        self.trips += prog[P_TRIPS]
        prog[P_TRIPS] = 0

    def _one(self, out: "MutableSequence[int]", ch: int, before: bool) -> None:
        """``ChipBank.read``'s body for one channel (``before``: its chip's ``_ready`` and
        ``_before`` when it is a new chip, not done yet)."""
        chip = self.chip_of[ch]
        self._read_channel(out, ch, before and (ch == 0 or self.chip_of[ch - 1] != chip))

    def _before(self, chip: int) -> None:
        self.flags[chip] = self._get(chip, REG_MASK)

    def _sample(self, ch: int) -> int:
        chip = self.chip_of[ch]
        k = self.input_of[ch]
        if self.flags[chip] & (CF1 >> k):
            self.flags[chip] &= ~(CF1 >> k)
            self.trips += 1
            return TRIPPED
        buf = self.buf  # _get inlined: this runs for every channel every tick
        self.rd(self.chips[chip], 1 + 2 * k, buf)
        if buf[0] & 0x80:
            return 0  # current flowing back: none drawn
        return (((buf[0] << 8) | buf[1]) >> 3) * 40000 // self.shunt_uohm  # 40 uV/LSB, mA
