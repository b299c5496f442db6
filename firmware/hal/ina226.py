"""The INA226 current monitors of a board revision, driven so that the board can trust them.

One ``Ina226Bank`` owns the chips of all channels on one I2C bus (``i2c`` is a
``machine.I2C``, passed in). ``setup()`` at boot checks each chip's manufacturer (FE = 0x5449)
and die (FF = 0x2260) IDs and configures it; ``read(out)`` fills one current per channel in mA,
or -1 for a channel whose chip gives no reading (the HAL contract: the channel then raises
``F_SENSOR``, see ``firmware/channel.py``).

Configuration for the 10 ms protection tick (TI SBOS547, CONFIG register): AVG = 4,
VBUSCT = VSHCT = 1.1 ms, shunt and bus continuous, CONFIG = 0x4327. A new averaged result
every (VBUSCT + VSHCT) x AVG = (1.1 + 1.1) x 4 = 8.8 ms, less than the 10 ms tick, so every
tick reads a result at most 8.8 ms old, averaged over 4 shunt conversions (4.4 ms of the
8.8 ms integrated: noise down by 2, a spike shorter than a conversion weighed by 1/4).
CALIBRATION = 0.00512 / (I_LSB x R_shunt) with I_LSB = 250 uA: 2048 for 10 mOhm (CURRENT
then reads in 250 uA steps up to +-8.19 A, the shunt's full scale of 81.92 mV); the board's
own reading is the SHUNT register (2.5 uV/LSB) over the shunt, which needs no calibration.

Trust: a chip that does not answer (``OSError`` ENODEV, a NACK) reads -1 and is configured
again when it answers; a bus held low (``ETIMEDOUT``) reads -1 on every channel of the bus and
is tried again every ``BUS_RETRY_TICKS`` reads (a stuck bus costs the I2C timeout each try); a
chip with the wrong IDs (another part at the address) reads -1 until the next boot. Every read
checks one chip's CONFIG in turn (10 chips: each every 100 ms); a chip found back at power-on
(a brown-out of the chip: CONFIG 0x4127, CALIBRATION 0) is configured again (``resets``).
"""

import errno

from protocol.compat import const

REG_CONFIG = const(0x00)
REG_SHUNT = const(0x01)
REG_CALIBRATION = const(0x05)
REG_MANUFACTURER = const(0xFE)
REG_DIE = const(0xFF)
MANUFACTURER = const(0x5449)
DIE = const(0x2260)
CONFIG_TICK = const(0x4327)  # AVG 4, VBUSCT 1.1 ms, VSHCT 1.1 ms, shunt and bus continuous
CURRENT_LSB_UA = const(250)
BUS_RETRY_TICKS = const(10)

# per chip
C_UNKNOWN = const(0)  # not configured (boot, or it stopped answering)
C_OK = const(1)
C_WRONG = const(2)  # another chip at the address: never trusted


def calibration(shunt_uohm: int) -> int:
    """CAL = 0.00512 / (I_LSB x R) in integers: 5.12e9 / (I_LSB[uA] x R[uOhm])."""
    return 5120000000 // (CURRENT_LSB_UA * shunt_uohm)


class Ina226Bank:
    def __init__(self, i2c: object, addrs: tuple, shunt_uohm: int) -> None:  # type: ignore[type-arg]
        self.i2c = i2c
        self.addrs = addrs
        self.n = len(addrs)
        self.shunt_uohm = shunt_uohm
        self.state = [C_UNKNOWN] * self.n
        self.ids = [0] * self.n  # (manufacturer << 16) | die, as last read
        self.buf = bytearray(2)
        self.wbuf = bytearray(2)
        self.check_i = 0
        self.bus_wait = 0  # reads left before a bus that timed out is tried again
        self.resets = 0  # chips found back at power-on and configured again
        self.errors = 0  # transactions that failed

    def _get(self, ch: int, reg: int) -> int:
        self.i2c.readfrom_mem_into(self.addrs[ch], reg, self.buf)  # type: ignore[attr-defined]
        return (self.buf[0] << 8) | self.buf[1]

    def _put(self, ch: int, reg: int, value: int) -> None:
        self.wbuf[0] = value >> 8
        self.wbuf[1] = value & 0xFF
        self.i2c.writeto_mem(self.addrs[ch], reg, self.wbuf)  # type: ignore[attr-defined]

    def _configure(self, ch: int) -> None:
        """Check the IDs and configure one chip; ``OSError`` if it does not answer."""
        self.ids[ch] = (self._get(ch, REG_MANUFACTURER) << 16) | self._get(ch, REG_DIE)
        if self.ids[ch] != (MANUFACTURER << 16) | DIE:
            self.state[ch] = C_WRONG
            return
        self._put(ch, REG_CONFIG, CONFIG_TICK)
        self._put(ch, REG_CALIBRATION, calibration(self.shunt_uohm))
        self.state[ch] = C_OK

    def _failed(self, ch: int, exc: OSError) -> bool:
        """A transaction failed: True when the whole bus is down (held low)."""
        self.errors += 1
        if self.state[ch] == C_OK:
            self.state[ch] = C_UNKNOWN
        if exc.args and exc.args[0] == errno.ETIMEDOUT:
            self.bus_wait = BUS_RETRY_TICKS
            return True
        return False

    def setup(self) -> None:
        """At boot: every chip's IDs checked and configured (those that answer)."""
        for ch in range(self.n):
            try:
                self._configure(ch)
            except OSError as exc:
                if self._failed(ch, exc):
                    return

    def report(self) -> list:  # type: ignore[type-arg]
        """One line per chip, as the board prints them at boot: ``ch0 0x40 ina226 ok``, ``ch1
        0x41 no answer``, ``ch2 0x42 wrong chip 5449:3220``, ``ch3 0x43 bus held low``."""
        out = []
        for ch in range(self.n):
            st = self.state[ch]
            if st == C_OK:
                what = "ina226 ok"
            elif st == C_WRONG:
                i = self.ids[ch]
                what = "wrong chip %04x:%04x" % (i >> 16, i & 0xFFFF)
            elif self.bus_wait:
                what = "bus held low"
            else:
                what = "no answer"
            out.append("ch%d 0x%02x %s" % (ch, self.addrs[ch], what))
        return out

    def read_one(self, ch: int) -> int:
        """One channel's current in mA (>= 0), or -1: no reading."""
        st = self.state[ch]
        if st == C_WRONG or self.bus_wait:
            return -1
        try:
            if st == C_UNKNOWN:
                self._configure(ch)
                if self.state[ch] != C_OK:
                    return -1
            raw = self._get(ch, REG_SHUNT)
        except OSError as exc:
            self._failed(ch, exc)
            return -1
        if raw & 0x8000:
            return 0  # current flowing back: none drawn
        return raw * 2500 // self.shunt_uohm  # 2.5 uV/LSB over the shunt, in mA

    def read(self, out: list) -> None:  # type: ignore[type-arg]
        """Every channel's current into ``out``; then one chip's configuration checked."""
        if self.bus_wait:
            self.bus_wait -= 1
            for ch in range(self.n):
                out[ch] = -1
            return
        for ch in range(self.n):
            out[ch] = self.read_one(ch)
        self._check()

    def _check(self) -> None:
        ch = self.check_i
        self.check_i = (ch + 1) % self.n
        if self.state[ch] != C_OK or self.bus_wait:
            return
        try:
            if self._get(ch, REG_CONFIG) != CONFIG_TICK:
                self.resets += 1
                self._configure(ch)
        except OSError as exc:
            self._failed(ch, exc)
