"""TI INA3221 triple-channel shunt and bus monitor, register by register, from the datasheet
(SBOS576).

The chip converts, for each enabled channel in turn (1, 2, 3), the shunt voltage (IN+ - IN-)
and the bus voltage with one ADC; ``sources[ch](t_us) -> (shunt_v, bus_v)`` is what channel
``ch``'s pins see. Timing, conversions and the part faults are ``emulator.parts.regchip``'s
(shared with the INA226); the registers are this chip's. There is no calibration register and
no current or power register: the host of the chip divides the shunt voltage by the shunt.

Registers (16 bit, big-endian; a write is pointer, MSB, LSB):

=======  ============  =====================================================================
00       CONFIG        power-on 0x7127; bit 15 RST; 14-12 channel 1-3 enable; 11-9 AVG (1, 4,
                       16, 64, 128, 256, 512, 1024); 8-6 VBUSCT, 5-3 VSHCT (140, 204, 332,
                       588, 1100, 2116, 4156, 8244 us); 2-0 MODE (0/4 power-down, 1-3
                       triggered shunt/bus/both, 5-7 continuous). A write restarts the cycle.
01/03/05 SHUNT 1-3     12 bits + sign, 40 uV/LSB, left-aligned by 3 (bits 2-0 read 0),
                       saturating at +-163.8 mV
02/04/06 BUS 1-3       8 mV/LSB, left-aligned by 3, 0 for a negative input, at most 32.76 V
07/09/0B CRITICAL 1-3  shunt format; compared with *every* shunt conversion of the channel (not
                       the average): over it, CFn (and the CRITICAL pin). Power-on 0x7FF8
08/0A/0C WARNING 1-3   shunt format; compared with the channel's *averaged* result: WFn (and
                       the WARNING pin). Power-on 0x7FF8
0D       SHUNT-SUM     the sum of the averaged shunt results of the channels selected by SCCn,
                       14 bits + sign, 40 uV/LSB, left-aligned by 1
0E       SUM LIMIT     SHUNT-SUM format, power-on 0x7FFE; SUM over it sets SF (CRITICAL pin)
0F       MASK/ENABLE   14-12 SCC1-3, 11 WEN (warning latch), 10 CEN (critical latch), read-only
                       flags 9-7 CF1-3, 6 SF, 5-3 WF1-3, 2 PVF, 1 TCF, 0 CVRF. Power-on 0x0002.
                       Reading clears CVRF, and CF/SF when CEN, WF when WEN (else those flags
                       follow the latest conversion)
10       PV UPPER      bus format, power-on 0x2710 (10 V); every enabled bus above it: PVF 1
11       PV LOWER      bus format, power-on 0x2328 (9 V); any enabled bus below it: PVF 0
FE       MANUFACTURER  0x5449
FF       DIE ID        0x3220
=======  ============  =====================================================================

Timing: one averaging round converts, for each enabled channel, its shunt then its bus (in
shunt-and-bus mode); AVG rounds make one result, so a new result every sum over the enabled
channels of (VBUSCT + VSHCT), times AVG; then CVRF. TCF (the timing-control flag) is modelled
as its power-on 1: the TC sequence after power-up is not.
"""

from emulator.parts.regchip import (
    AVERAGES,
    CONV_US,
    FAULTS,
    RegisterChip,
    signed,
    trunc_div,
)

__all__ = ["AVERAGES", "CONV_US", "FAULTS", "Ina3221"]

CONFIG = 0x00
MASK_ENABLE = 0x0F
SHUNT_SUM = 0x0D
SUM_LIMIT = 0x0E
PV_UPPER = 0x10
PV_LOWER = 0x11

CONFIG_POR = 0x7127
DIE = 0x3220
SHUNT_LSB_V = 40e-6
BUS_LSB_V = 8e-3

SCC1 = 0x4000
WEN = 0x0800
CEN = 0x0400
CF1 = 0x0200
SF = 0x0040
WF1 = 0x0020
PVF = 0x0004
TCF = 0x0002
CVRF = 0x0001
MASK_WRITABLE = 0x7C00
CF_ALL = CF1 | CF1 >> 1 | CF1 >> 2
WF_ALL = WF1 | WF1 >> 1 | WF1 >> 2


def shunt_reg(ch: int) -> int:
    """SHUNT register of channel ``ch`` (0-2)."""
    return 1 + 2 * ch


def bus_reg(ch: int) -> int:
    return 2 + 2 * ch


def critical_reg(ch: int) -> int:
    return 7 + 2 * ch


def warning_reg(ch: int) -> int:
    return 8 + 2 * ch


def config_word(avg: int, vbusct_us: int, vshct_us: int, mode: int = 7,
                channels: int = 7) -> int:
    """CONFIG for an averaging count, conversion times (datasheet units) and the enabled
    channels (bit 0 = channel 1): ``config_word(1, 1100, 1100)`` = 0x7127, the power-on value."""
    ch = ((channels & 1) << 2) | (channels & 2) | ((channels & 4) >> 2)
    return (ch << 12 | AVERAGES.index(avg) << 9 | CONV_US.index(vbusct_us) << 6
            | CONV_US.index(vshct_us) << 3 | mode)


def cycle_us(config: int) -> int:
    """Microseconds from one result to the next in a continuous mode: the sum over enabled
    channels of (VBUSCT + VSHCT), times AVG (VSHCT or VBUSCT alone in a one-input mode)."""
    per = 0
    if config & 1:
        per += CONV_US[(config >> 3) & 7]
    if config & 2:
        per += CONV_US[(config >> 6) & 7]
    n = (config >> 14 & 1) + (config >> 13 & 1) + (config >> 12 & 1)
    return n * per * AVERAGES[(config >> 9) & 7]


def shunt_code(reg: int) -> int:
    """A shunt-format register as its signed count of 40 uV."""
    return signed(reg) >> 3


class Ina3221(RegisterChip):
    NAME = "INA3221"
    DIE = 0x3220
    N_CHANNELS = 3

    def power_on_values(self) -> "list[int]":
        return [CONFIG_POR, 0, 0, 0, 0, 0, 0, 0x7FF8, 0x7FF8, 0x7FF8, 0x7FF8, 0x7FF8, 0x7FF8,
                0, 0x7FFE, TCF, 0x2710, 0x2328]

    def enabled(self, ch: int) -> bool:
        return bool(self.regs[CONFIG] & (0x4000 >> ch))

    # --- conversions ---------------------------------------------------------------------

    def _round(self, cfg: int) -> "list[tuple[int, int, int]]":
        seq = []
        for ch in range(3):
            if not cfg & (0x4000 >> ch):
                continue
            if cfg & 1:
                seq.append((1, ch, CONV_US[(cfg >> 3) & 7]))
            if cfg & 2:
                seq.append((2, ch, CONV_US[(cfg >> 6) & 7]))
        return seq

    def _clear_acc(self) -> None:
        self.acc_shunt = [0, 0, 0]
        self.acc_bus = [0, 0, 0]

    def _take(self, kind: int, ch: int, t_us: int) -> None:
        shunt_v, bus_v = self.sources[ch](t_us)
        if kind == 1:
            code = round(self.shunt_input(shunt_v) / SHUNT_LSB_V)
            code = 4095 if code > 4095 else -4096 if code < -4096 else code
            self.acc_shunt[ch] += code
            self._critical(ch, code)
        else:
            code = round(bus_v / BUS_LSB_V)
            self.acc_bus[ch] += 0 if code < 0 else 4095 if code > 4095 else code

    def _critical(self, ch: int, code: int) -> None:
        """Every shunt conversion against the channel's critical limit (CFn)."""
        regs = self.regs
        bit = CF1 >> ch
        if code > shunt_code(regs[critical_reg(ch)]):
            regs[MASK_ENABLE] |= bit
        elif not regs[MASK_ENABLE] & CEN:
            regs[MASK_ENABLE] &= ~bit

    def _finish(self, avg: int) -> None:
        regs = self.regs
        cfg = regs[CONFIG]
        me = regs[MASK_ENABLE]
        if not self.stuck:
            for ch in range(3):
                if not self.enabled(ch):
                    continue
                if cfg & 1:
                    regs[shunt_reg(ch)] = (trunc_div(self.acc_shunt[ch], avg) << 3) & 0xFFFF
                if cfg & 2:
                    regs[bus_reg(ch)] = (self.acc_bus[ch] // avg) << 3
        total = 0
        pv_hi = True
        pv_lo = False
        for ch in range(3):
            code = shunt_code(regs[shunt_reg(ch)])
            if me & (SCC1 >> ch):
                total += code
            if not self.enabled(ch):
                continue
            bit = WF1 >> ch
            if code > shunt_code(regs[warning_reg(ch)]):
                me |= bit
            elif not me & WEN:
                me &= ~bit
            bus = regs[bus_reg(ch)]
            if bus <= regs[PV_UPPER]:
                pv_hi = False
            if bus < regs[PV_LOWER]:
                pv_lo = True
        total = 16383 if total > 16383 else -16384 if total < -16384 else total
        regs[SHUNT_SUM] = (total << 1) & 0xFFFF
        if total > signed(regs[SUM_LIMIT]) >> 1:
            me |= SF
        elif not me & CEN:
            me &= ~SF
        if pv_hi:
            me |= PVF
        elif pv_lo:
            me &= ~PVF
        regs[MASK_ENABLE] = me | CVRF

    def critical_pin(self) -> int:
        """The open-drain CRITICAL output as a pulled-up line reads it (0: asserted)."""
        return 0 if self.regs[MASK_ENABLE] & (CF_ALL | SF) else 1

    def warning_pin(self) -> int:
        return 0 if self.regs[MASK_ENABLE] & WF_ALL else 1

    def pv_pin(self) -> int:
        """PV (open drain): released high while every enabled bus is in its valid range."""
        return 1 if self.regs[MASK_ENABLE] & PVF else 0

    # --- registers -----------------------------------------------------------------------

    def _read(self, reg: int) -> int:
        v = self.regs[reg]
        if reg == MASK_ENABLE:
            me = v & ~CVRF
            if me & CEN:
                me &= ~(CF_ALL | SF)
            if me & WEN:
                me &= ~WF_ALL
            self.regs[MASK_ENABLE] = me
        return v

    def _write(self, reg: int, value: int, now_us: int) -> None:
        regs = self.regs
        if reg == CONFIG:
            if value & 0x8000:
                self.power_on_reset(now_us)
                return
            regs[CONFIG] = value & 0x7FFF
            regs[MASK_ENABLE] &= ~CVRF
            self._restart(now_us)
        elif 7 <= reg <= 0x0C:
            regs[reg] = value & 0xFFF8
        elif reg == SUM_LIMIT:
            regs[reg] = value & 0xFFFE
        elif reg == MASK_ENABLE:
            regs[reg] = (regs[reg] & ~MASK_WRITABLE) | (value & MASK_WRITABLE)
        elif reg in (PV_UPPER, PV_LOWER):
            regs[reg] = value & 0x7FF8
        # SHUNT, BUS, SHUNT-SUM and the IDs are read-only: the write is ignored
