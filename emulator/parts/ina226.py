"""TI INA226 current/power monitor, register by register, from the datasheet (SBOS547).

The chip measures the differential voltage across a shunt (IN+ - IN-) and the bus voltage
(VBUS) with one ADC, alternately; ``source(t_us) -> (shunt_v, bus_v)`` is what its pins see at
simulated time ``t_us`` (the board's electronics supply it). ``advance(now_us)`` runs the
conversions due up to ``now_us``; the I2C bus calls it before every transaction, so a register
read returns what the chip would hold at that instant.

Registers (16 bit, big-endian on the wire; a write is pointer, MSB, LSB; a read returns the
register the pointer names):

====  ===========  ===========================================================================
00    CONFIG       power-on 0x4127; bit 15 RST (all registers back to power-on, reads 0);
                   bits 11-9 AVG (1, 4, 16, 64, 128, 256, 512, 1024 samples), 8-6 VBUSCT and
                   5-3 VSHCT (140, 204, 332, 588, 1100, 2116, 4156, 8244 us), 2-0 MODE (0/4
                   power-down, 1-3 triggered shunt/bus/both, 5-7 continuous); bit 14 reads 1.
                   A write restarts the conversion cycle and clears CVRF.
01    SHUNT        signed, 2.5 uV/LSB, saturating at 0x7FFF / 0x8000 (+-81.92 mV)
02    BUS          1.25 mV/LSB, 0 for a negative input, at most 0x7FFF
03    POWER        CURRENT x BUS / 20000 (LSB = 25 x current LSB), unsigned
04    CURRENT      SHUNT x CALIBRATION / 2048, signed (0 while CALIBRATION is 0)
05    CALIBRATION  power-on 0; bit 15 reads 0; CAL = 0.00512 / (current LSB x R_shunt)
06    MASK/ENABLE  15 SOL, 14 SUL, 13 BOL, 12 BUL, 11 POL, 10 CNVR (one alert function: the
                   highest set bit wins), 4 AFF, 3 CVRF, 2 OVF (read-only flags), 1 APOL,
                   0 LEN (latch). Reading it clears CVRF, and AFF when latched.
07    ALERT LIMIT  compared with SHUNT (signed), BUS or POWER after each averaged result
FE    MANUFACTURER 0x5449 ("TI")
FF    DIE ID       0x2260
====  ===========  ===========================================================================

Timing: one result every (VBUSCT + VSHCT) x AVG in shunt-and-bus mode (VSHCT x AVG or
VBUSCT x AVG for one input), shunt first, run by ``emulator.parts.regchip`` (which also holds
the part faults this chip shares with the INA3221: ``nack``, ``stuck_low``, ``reset``
(CALIBRATION back to 0 with the rest), ``stuck``, ``open_shunt``, ``gain``, ``noise``,
``die_id``). After each averaged result CVRF and the alert are set.
"""

from emulator.parts.regchip import (
    AVERAGES,
    CONV_US,
    DIE_ID,
    FAULTS,
    MANUFACTURER,
    MANUFACTURER_ID,
    RegisterChip,
    signed,
    trunc_div,
)

__all__ = ["AVERAGES", "CONV_US", "DIE_ID", "FAULTS", "MANUFACTURER", "MANUFACTURER_ID", "Ina226"]

CONFIG = 0x00
SHUNT = 0x01
BUS = 0x02
POWER = 0x03
CURRENT = 0x04
CALIBRATION = 0x05
MASK_ENABLE = 0x06
ALERT_LIMIT = 0x07

CONFIG_POR = 0x4127
DIE = 0x2260
SHUNT_LSB_V = 2.5e-6
BUS_LSB_V = 1.25e-3

SOL = 0x8000
SUL = 0x4000
BOL = 0x2000
BUL = 0x1000
POL = 0x0800
CNVR = 0x0400
AFF = 0x0010
CVRF = 0x0008
OVF = 0x0004
APOL = 0x0002
LEN = 0x0001
ALERT_FUNCTIONS = (SOL, SUL, BOL, BUL, POL, CNVR)
MASK_WRITABLE = 0xFC03


def config_word(avg: int, vbusct_us: int, vshct_us: int, mode: int = 7) -> int:
    """The CONFIG value for an averaging count and conversion times named in the datasheet's
    units (``config_word(4, 1100, 1100)`` = 0x4327)."""
    return (0x4000 | AVERAGES.index(avg) << 9 | CONV_US.index(vbusct_us) << 6
            | CONV_US.index(vshct_us) << 3 | mode)


def cycle_us(config: int) -> int:
    """Microseconds from one result to the next in a continuous mode, (VBUSCT + VSHCT) x AVG."""
    mode = config & 7
    avg = AVERAGES[(config >> 9) & 7]
    t = 0
    if mode & 1:
        t += CONV_US[(config >> 3) & 7]
    if mode & 2:
        t += CONV_US[(config >> 6) & 7]
    return t * avg


_signed = signed
_trunc_div = trunc_div


class Ina226(RegisterChip):
    NAME = "INA226"
    DIE = 0x2260

    def __init__(self, source: object = None, seed: int = 1, now_us: int = 0) -> None:
        super().__init__(None if source is None else [source], seed, now_us)

    @property
    def source(self) -> object:
        """What the chip's pins see: ``source(t_us) -> (shunt_v, bus_v)``."""
        return self.sources[0]

    @source.setter
    def source(self, fn: object) -> None:
        self.sources[0] = fn

    def power_on_values(self) -> "list[int]":
        return [CONFIG_POR, 0, 0, 0, 0, 0, 0, 0]

    # --- conversions ---------------------------------------------------------------------

    def _round(self, cfg: int) -> "list[tuple[int, int, int]]":
        mode = cfg & 3
        seq = []
        if mode & 1:
            seq.append((1, 0, CONV_US[(cfg >> 3) & 7]))
        if mode & 2:
            seq.append((2, 0, CONV_US[(cfg >> 6) & 7]))
        return seq

    def _clear_acc(self) -> None:
        self.acc_shunt = 0
        self.acc_bus = 0

    def _take(self, kind: int, ch: int, t_us: int) -> None:
        shunt_v, bus_v = self.sources[0](t_us)
        if kind == 1:
            code = round(self.shunt_input(shunt_v) / SHUNT_LSB_V)
            self.acc_shunt += 32767 if code > 32767 else -32768 if code < -32768 else code
        else:
            code = round(bus_v / BUS_LSB_V)
            self.acc_bus += 0 if code < 0 else 0x7FFF if code > 0x7FFF else code

    def _finish(self, avg: int) -> None:
        regs = self.regs
        mode = regs[CONFIG] & 3
        if not self.stuck:
            if mode & 1:
                regs[SHUNT] = _trunc_div(self.acc_shunt, avg) & 0xFFFF
            if mode & 2:
                regs[BUS] = self.acc_bus // avg
            ovf = 0
            cur = _trunc_div(_signed(regs[SHUNT]) * regs[CALIBRATION], 2048)
            if cur > 32767 or cur < -32768:
                ovf = OVF
                cur = 32767 if cur > 0 else -32768
            regs[CURRENT] = cur & 0xFFFF
            pwr = abs(cur) * regs[BUS] // 20000
            if pwr > 0xFFFF:
                ovf = OVF
                pwr = 0xFFFF
            regs[POWER] = pwr
            regs[MASK_ENABLE] = (regs[MASK_ENABLE] & ~OVF) | ovf
        regs[MASK_ENABLE] |= CVRF
        self._alert()

    def _function(self) -> int:
        me = self.regs[MASK_ENABLE]
        for bit in ALERT_FUNCTIONS:
            if me & bit:
                return bit
        return 0

    def _alert(self) -> None:
        regs = self.regs
        fn = self._function()
        limit = regs[ALERT_LIMIT]
        hit = False
        if fn == SOL:
            hit = _signed(regs[SHUNT]) > _signed(limit)
        elif fn == SUL:
            hit = _signed(regs[SHUNT]) < _signed(limit)
        elif fn == BOL:
            hit = regs[BUS] > limit
        elif fn == BUL:
            hit = regs[BUS] < limit
        elif fn == POL:
            hit = regs[POWER] > limit
        elif fn == CNVR:
            hit = True
        if hit:
            regs[MASK_ENABLE] |= AFF
        elif not regs[MASK_ENABLE] & LEN:
            regs[MASK_ENABLE] &= ~AFF  # transparent: follows the latest result

    def alert_pin(self) -> int:
        """The open-drain ALERT output as a pulled-up line reads it (1 idle, 0 asserted with
        APOL = 0; inverted with APOL = 1)."""
        me = self.regs[MASK_ENABLE]
        asserted = bool(me & CVRF) if self._function() == CNVR else bool(me & AFF)
        if me & APOL:
            return 1 if asserted else 0
        return 0 if asserted else 1

    # --- the I2C side ------------------------------------------------------------------------

    def _read(self, reg: int) -> int:
        v = self.regs[reg]
        if reg == MASK_ENABLE:
            me = v & ~CVRF
            if me & LEN:
                me &= ~AFF
            self.regs[MASK_ENABLE] = me
        return v

    def _write(self, reg: int, value: int, now_us: int) -> None:
        if reg == CONFIG:
            if value & 0x8000:
                self.power_on_reset(now_us)
                return
            self.regs[CONFIG] = (value & 0x0FFF) | 0x4000
            self.regs[MASK_ENABLE] &= ~CVRF
            self._restart(now_us)
        elif reg == CALIBRATION:
            self.regs[CALIBRATION] = value & 0x7FFF
        elif reg == MASK_ENABLE:
            self.regs[MASK_ENABLE] = (self.regs[MASK_ENABLE] & ~MASK_WRITABLE) \
                | (value & MASK_WRITABLE)
        elif reg == ALERT_LIMIT:
            self.regs[ALERT_LIMIT] = value & 0xFFFF
        # SHUNT, BUS, POWER, CURRENT and the IDs are read-only: the write is ignored
