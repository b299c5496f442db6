"""The INA226 current monitors of a board revision (TI SBOS547), one per channel.

``Ina226Bank`` is a ``firmware.hal.chipbank.ChipBank`` (IDs checked at boot, a chip that does
not answer or a bus held low read as ``NO_READING``, a chip that reset configured again):
``i2c`` is a ``machine.I2C``, passed in; ``addrs`` one address per channel.

Configuration for the 10 ms protection tick (CONFIG register): AVG = 4, VBUSCT = VSHCT =
1.1 ms, shunt and bus continuous, CONFIG = 0x4327. A new averaged result every (VBUSCT +
VSHCT) x AVG = (1.1 + 1.1) x 4 = 8.8 ms, less than the 10 ms tick, so every tick reads a
result at most 8.8 ms old, averaged over 4 shunt conversions (4.4 ms of the 8.8 ms integrated:
noise down by 2, a spike shorter than a conversion weighed by 1/4). CALIBRATION = 0.00512 /
(I_LSB x R_shunt) with I_LSB = 250 uA: 2048 for 10 mOhm (CURRENT then reads in 250 uA steps up
to +-8.19 A, the shunt's full scale of 81.92 mV); the board's own reading is the SHUNT
register (2.5 uV/LSB) over the shunt, which needs no calibration. Per tick on the bus: one
SHUNT read per channel and one CONFIG check (10 chips: each checked every 100 ms).
"""

from firmware.fast import ina226_read
from firmware.hal import NO_READING
from firmware.hal.chipbank import P_AT, P_RESET, ChipBank
from protocol.compat import const

if False:  # typing only (compiled away on the board)
    from collections.abc import MutableSequence

    from firmware.hal.chipbank import I2c

REG_CONFIG = const(0x00)
REG_SHUNT = const(0x01)
REG_CALIBRATION = const(0x05)
DIE = 0x2260
CONFIG_TICK = 0x4327  # AVG 4, VBUSCT 1.1 ms, VSHCT 1.1 ms, shunt and bus continuous
CURRENT_LSB_UA = const(250)


def calibration(shunt_uohm: int) -> int:
    """CAL = 0.00512 / (I_LSB x R) in integers: 5.12e9 / (I_LSB[uA] x R[uOhm])."""
    return 5120000000 // (CURRENT_LSB_UA * shunt_uohm)


class Ina226Bank(ChipBank):
    NAME = "ina226"
    DIE = 0x2260
    CONFIG_TICK = 0x4327

    def __init__(self, i2c: "I2c", addrs: "tuple[int, ...]", shunt_uohm: int) -> None:
        n = len(addrs)
        super().__init__(i2c, addrs, list(range(n)), [0] * n)
        self.addrs = addrs
        self.shunt_uohm = shunt_uohm
        self.addr_b = bytes(addrs)  # for the viper read

    def _write_config(self, chip: int) -> None:
        self._put(chip, REG_CONFIG, CONFIG_TICK)
        self._put(chip, REG_CALIBRATION, calibration(self.shunt_uohm))

    def read(self, out: "MutableSequence[int]") -> None:
        """As ``ChipBank.read`` (a chip a channel, no per-tick flags), each run of ready chips
        read by ``firmware.fast.ina226_read``, which also checks a chip's CONFIG when it took
        every channel left (``ChipBank._check``; else ``_check`` does it here)."""
        if self.bus_wait:
            ChipBank.read(self, out)
            return
        n = self.n
        prog = self.prog
        ch = 0
        while ch < n:
            if not self.bus_wait:
                try:
                    ch = ina226_read(self.rd, self.addr_b, self.state, self.buf, out, ch, n,
                                     self.shunt_uohm, prog, self.configs)
                except OSError as exc:
                    ch = prog[P_AT]
                    if ch >= n:  # the CONFIG check's read, after every channel
                        self._checked(exc)
                        return
                    self._failed(ch, exc)
                    out[ch] = NO_READING
                    ch += 1
                    continue
                if ch > n:  # every channel read and a CONFIG checked
                    if prog[P_RESET]:
                        self._checked(None)
                    return
            self._read_channel(out, ch, True)  # a chip not ready, or a bus down since
            ch += 1
        self._check()

    def _sample(self, ch: int) -> int:
        buf = self.buf  # _get inlined: this runs for every channel every tick
        self.rd(self.chips[ch], REG_SHUNT, buf)
        if buf[0] & 0x80:
            return 0  # current flowing back: none drawn
        return ((buf[0] << 8) | buf[1]) * 2500 // self.shunt_uohm  # 2.5 uV/LSB, in mA
