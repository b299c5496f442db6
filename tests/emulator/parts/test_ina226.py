"""The INA226 model against the numbers of TI's datasheet (SBOS547), not against our driver.

Runs under pytest and under the real MicroPython (``micropython tests/mpy_run.py
tests/emulator/parts``). Registers are read and written the way a bus master does: a pointer
byte, then MSB and LSB.
"""

import unittest

from emulator.parts import ina226 as I
from emulator.parts.ina226 import Ina226


class Inputs:
    """What the chip's pins see: a shunt voltage and a bus voltage, settable, or a function."""

    def __init__(self, shunt_v=0.0, bus_v=0.0):
        self.shunt_v = shunt_v
        self.bus_v = bus_v
        self.fn = None

    def __call__(self, t_us):
        if self.fn is not None:
            return self.fn(t_us)
        return self.shunt_v, self.bus_v


def rd(chip, reg, t):
    chip.i2c_write(bytes([reg]), t)
    got = chip.i2c_read(2, t)
    return (got[0] << 8) | got[1]


def wr(chip, reg, value, t):
    chip.i2c_write(bytes([reg, value >> 8, value & 0xFF]), t)


def signed(v):
    return v - 0x10000 if v & 0x8000 else v


def spread(vals):
    """The mean and the rms deviation of ``vals``."""
    mean = sum(vals) / len(vals)
    return mean, (sum((v - mean) ** 2 for v in vals) / len(vals)) ** 0.5


def chip_with(shunt_v=0.0, bus_v=0.0):
    inputs = Inputs(shunt_v, bus_v)
    return Ina226(inputs), inputs


class PowerOnTest(unittest.TestCase):
    def test_power_on_values_and_ids(self):
        c, _ = chip_with()
        self.assertEqual(rd(c, I.CONFIG, 0), 0x4127)
        for reg in (I.CALIBRATION, I.MASK_ENABLE, I.ALERT_LIMIT, I.CURRENT, I.POWER):
            self.assertEqual(rd(c, reg, 0), 0)
        self.assertEqual(rd(c, 0xFE, 0), 0x5449)
        self.assertEqual(rd(c, 0xFF, 0), 0x2260)

    def test_power_on_config_decodes_as_the_datasheet_says(self):
        # 0x4127: AVG 1, VBUSCT 1.1 ms, VSHCT 1.1 ms, shunt and bus continuous
        self.assertEqual(I.config_word(1, 1100, 1100, 7), 0x4127)
        self.assertEqual(I.cycle_us(0x4127), 2200)

    def test_reset_bit_restores_every_register_and_reads_back_clear(self):
        c, _ = chip_with(0.010, 12.0)
        wr(c, I.CONFIG, I.config_word(16, 588, 588), 0)
        wr(c, I.CALIBRATION, 2560, 0)
        wr(c, I.ALERT_LIMIT, 1234, 0)
        wr(c, I.MASK_ENABLE, I.SOL, 0)
        wr(c, I.CONFIG, 0x8000 | I.config_word(16, 588, 588), 10)
        self.assertEqual(rd(c, I.CONFIG, 10), 0x4127)
        for reg in (I.CALIBRATION, I.ALERT_LIMIT, I.MASK_ENABLE, I.SHUNT, I.BUS):
            self.assertEqual(rd(c, reg, 10), 0)

    def test_config_bits_14_to_12_read_as_the_datasheet_says(self):
        c, _ = chip_with()
        wr(c, I.CONFIG, 0x0127, 0)  # bit 14 written 0 still reads 1
        self.assertEqual(rd(c, I.CONFIG, 0), 0x4127)
        wr(c, I.CONFIG, 0x7127, 0)  # bits 13-12 are not writable
        self.assertEqual(rd(c, I.CONFIG, 0), 0x4127)


class ScaleTest(unittest.TestCase):
    def result(self, shunt_v, bus_v=0.0, cal=0):
        c, _ = chip_with(shunt_v, bus_v)
        if cal:
            wr(c, I.CALIBRATION, cal, 0)
        return c, {r: rd(c, r, 2200) for r in (I.SHUNT, I.BUS, I.CURRENT, I.POWER)}

    def test_shunt_is_2_5_uv_per_lsb_twos_complement(self):
        self.assertEqual(self.result(0.010)[1][I.SHUNT], 4000)  # 10 mV
        self.assertEqual(self.result(-0.010)[1][I.SHUNT], 0xF060)  # -10 mV
        self.assertEqual(self.result(2.5e-6)[1][I.SHUNT], 0x0001)
        self.assertEqual(self.result(-2.5e-6)[1][I.SHUNT], 0xFFFF)

    def test_shunt_saturates_at_81_92_mv(self):
        self.assertEqual(self.result(0.0819175)[1][I.SHUNT], 0x7FFF)
        self.assertEqual(self.result(0.200)[1][I.SHUNT], 0x7FFF)
        self.assertEqual(self.result(-0.08192)[1][I.SHUNT], 0x8000)
        self.assertEqual(self.result(-0.500)[1][I.SHUNT], 0x8000)

    def test_bus_is_1_25_mv_per_lsb(self):
        self.assertEqual(self.result(0, 12.0)[1][I.BUS], 9600)
        self.assertEqual(self.result(0, 36.0)[1][I.BUS], 0x7080)
        self.assertEqual(self.result(0, -1.0)[1][I.BUS], 0)

    def test_calibration_zero_reads_current_and_power_zero(self):
        regs = self.result(0.010, 12.0)[1]
        self.assertEqual(regs[I.SHUNT], 4000)
        self.assertEqual(regs[I.CURRENT], 0)
        self.assertEqual(regs[I.POWER], 0)

    def test_the_datasheets_calibration_example(self):
        # 2 mOhm shunt, current LSB 1 mA: CAL = 0.00512 / (0.001 * 0.002) = 2560; 5 A gives
        # 10 mV (SHUNT 4000), CURRENT 4000 * 2560 / 2048 = 5000 (5 A); at 12 V (BUS 9600)
        # POWER 5000 * 9600 / 20000 = 2400, at 25 mW/LSB 60 W.
        cal = int(0.00512 / (0.001 * 0.002) + 0.5)
        self.assertEqual(cal, 2560)
        regs = self.result(5.0 * 0.002, 12.0, cal)[1]
        self.assertEqual(regs[I.CURRENT], 5000)
        self.assertEqual(regs[I.POWER], 2400)
        self.assertAlmostEqual(regs[I.POWER] * 25 * 0.001, 60.0, places=6)

    def test_negative_current_is_signed_and_power_positive(self):
        regs = self.result(-0.002, 12.0, 2560)[1]  # -1 A
        self.assertEqual(signed(regs[I.CURRENT]), -1000)
        self.assertEqual(regs[I.POWER], 1000 * 9600 // 20000)

    def test_calibration_bit_15_is_not_writable(self):
        c, _ = chip_with()
        wr(c, I.CALIBRATION, 0xFFFF, 0)
        self.assertEqual(rd(c, I.CALIBRATION, 0), 0x7FFF)

    def test_result_registers_are_read_only(self):
        c, _ = chip_with(0.010, 12.0)
        wr(c, I.SHUNT, 0x1234, 2200)
        wr(c, I.BUS, 0x1234, 2200)
        self.assertEqual(rd(c, I.SHUNT, 2200), 4000)
        self.assertEqual(rd(c, I.BUS, 2200), 9600)


class TimingTest(unittest.TestCase):
    def test_a_result_every_bus_plus_shunt_time_times_avg(self):
        c, _ = chip_with(0.010, 12.0)
        cfg = I.config_word(4, 1100, 1100)
        self.assertEqual(cfg, 0x4327)
        wr(c, I.CONFIG, cfg, 0)
        self.assertEqual(I.cycle_us(cfg), 8800)  # (1.1 ms + 1.1 ms) x 4
        self.assertEqual(rd(c, I.SHUNT, 8799), 0)
        self.assertFalse(rd(c, I.MASK_ENABLE, 8799) & I.CVRF)
        self.assertTrue(rd(c, I.MASK_ENABLE, 8800) & I.CVRF)
        self.assertEqual(rd(c, I.SHUNT, 8800), 4000)

    def test_cvrf_clears_on_reading_and_returns_each_cycle(self):
        c, _ = chip_with(0.010, 12.0)
        self.assertTrue(rd(c, I.MASK_ENABLE, 2200) & I.CVRF)
        self.assertFalse(rd(c, I.MASK_ENABLE, 2201) & I.CVRF)  # the read above cleared it
        self.assertTrue(rd(c, I.MASK_ENABLE, 4400) & I.CVRF)

    def test_writing_config_restarts_the_cycle_and_clears_cvrf(self):
        c, _ = chip_with(0.010, 12.0)
        c.advance(2200)
        wr(c, I.CONFIG, 0x4127, 3000)
        self.assertFalse(rd(c, I.MASK_ENABLE, 3000) & I.CVRF)
        self.assertFalse(rd(c, I.MASK_ENABLE, 5199) & I.CVRF)
        self.assertTrue(rd(c, I.MASK_ENABLE, 5200) & I.CVRF)

    def test_shunt_only_mode_leaves_bus_alone_and_runs_vshct_times_avg(self):
        c, _inputs = chip_with(0.010, 12.0)
        wr(c, I.CONFIG, I.config_word(16, 1100, 332, mode=5), 0)
        self.assertEqual(I.cycle_us(I.config_word(16, 1100, 332, mode=5)), 16 * 332)
        self.assertEqual(rd(c, I.SHUNT, 16 * 332), 4000)
        self.assertEqual(rd(c, I.BUS, 16 * 332), 0)

    def test_triggered_mode_converts_once(self):
        c, inputs = chip_with(0.010, 12.0)
        wr(c, I.CONFIG, I.config_word(1, 140, 140, mode=3), 0)
        self.assertEqual(rd(c, I.SHUNT, 280), 4000)
        inputs.shunt_v = 0.020
        self.assertEqual(rd(c, I.SHUNT, 10000), 4000)  # no new conversion
        wr(c, I.CONFIG, I.config_word(1, 140, 140, mode=3), 10000)  # a write triggers one
        self.assertEqual(rd(c, I.SHUNT, 10280), 8000)

    def test_power_down_converts_nothing(self):
        c, _ = chip_with(0.010, 12.0)
        wr(c, I.CONFIG, I.config_word(1, 140, 140, mode=0), 0)
        self.assertEqual(rd(c, I.SHUNT, 100000), 0)
        self.assertEqual(c.conversions, 0)

    def test_averaging_is_a_real_average(self):
        # AVG 4 at 140 us + 140 us: shunt conversions centred at 70, 350, 630, 910 us. A 20 mV
        # spike during only the first of them moves the result by a quarter.
        c, inputs = chip_with(0.0, 12.0)
        wr(c, I.CONFIG, I.config_word(4, 140, 140), 0)
        inputs.fn = lambda t: (0.020 if t < 280 else 0.0, 12.0)
        self.assertEqual(rd(c, I.SHUNT, 1120), 2000)  # 8000 / 4
        inputs.fn = None
        inputs.shunt_v = 0.004
        self.assertEqual(rd(c, I.SHUNT, 2240), 1600)

    def test_a_long_gap_keeps_the_latest_result(self):
        c, inputs = chip_with(0.010, 12.0)
        c.advance(1000000)
        inputs.shunt_v = 0.005
        self.assertEqual(rd(c, I.SHUNT, 3600000000), 2000)  # an hour later, fresh


class AlertTest(unittest.TestCase):
    def setup(self, mask, limit, shunt_v=0.010, bus_v=12.0):
        c, inputs = chip_with(shunt_v, bus_v)
        wr(c, I.ALERT_LIMIT, limit, 0)
        wr(c, I.MASK_ENABLE, mask, 0)
        return c, inputs

    def test_shunt_over_limit_asserts_alert_active_low(self):
        c, _ = self.setup(I.SOL, 3000)  # 4000 > 3000
        self.assertEqual(c.alert_pin(), 1)
        c.advance(2200)
        self.assertEqual(c.alert_pin(), 0)
        self.assertTrue(rd(c, I.MASK_ENABLE, 2200) & I.AFF)

    def test_apol_inverts_the_pin(self):
        c, _ = self.setup(I.SOL | I.APOL, 3000)
        self.assertEqual(c.alert_pin(), 0)
        c.advance(2200)
        self.assertEqual(c.alert_pin(), 1)

    def test_highest_alert_bit_wins(self):
        # SOL (bit 15) and BUL (bit 12) both set: the shunt is under the limit (4000 < 5000)
        # and the bus (9600) over it: only SOL counts, so no alert.
        c, _ = self.setup(I.SOL | I.BUL, 5000)
        c.advance(2200)
        self.assertEqual(c.alert_pin(), 1)
        self.assertFalse(c.regs[I.MASK_ENABLE] & I.AFF)

    def test_transparent_mode_follows_the_latest_result(self):
        c, inputs = self.setup(I.BOL, 10000)
        inputs.bus_v = 13.0  # 10400 > 10000
        c.advance(2200)
        self.assertEqual(c.alert_pin(), 0)
        inputs.bus_v = 12.0
        c.advance(4400)
        self.assertEqual(c.alert_pin(), 1)

    def test_latch_holds_until_mask_enable_is_read(self):
        c, inputs = self.setup(I.BOL | I.LEN, 10000)
        inputs.bus_v = 13.0
        c.advance(2200)
        inputs.bus_v = 12.0
        c.advance(4400)
        self.assertEqual(c.alert_pin(), 0)  # latched although the bus is back
        self.assertTrue(rd(c, I.MASK_ENABLE, 4400) & I.AFF)
        self.assertEqual(c.alert_pin(), 1)  # the read cleared it

    def test_conversion_ready_alert(self):
        c, _ = self.setup(I.CNVR, 0)
        self.assertEqual(c.alert_pin(), 1)
        c.advance(2200)
        self.assertEqual(c.alert_pin(), 0)
        rd(c, I.MASK_ENABLE, 2200)
        self.assertEqual(c.alert_pin(), 1)

    def test_power_over_limit_and_bus_under_limit(self):
        c, _ = self.setup(I.POL, 2000)
        wr(c, I.CALIBRATION, 2560, 0)  # 2 mOhm, 1 mA LSB: 10 mV is 5 A, 12 V: POWER 2400
        c.advance(2200)
        self.assertEqual(c.alert_pin(), 0)
        c2, _ = self.setup(I.BUL, 9601)
        c2.advance(2200)
        self.assertEqual(c2.alert_pin(), 0)

    def test_flag_bits_are_read_only(self):
        c, _ = self.setup(I.AFF | I.CVRF | I.OVF, 0)
        self.assertEqual(rd(c, I.MASK_ENABLE, 0), 0)

    def test_math_overflow_flag(self):
        c, _ = chip_with(0.080, 12.0)
        wr(c, I.CALIBRATION, 0x7FFF, 0)  # 32000 x 32767 / 2048 overflows CURRENT
        c.advance(2200)
        self.assertTrue(c.regs[I.MASK_ENABLE] & I.OVF)
        self.assertEqual(rd(c, I.CURRENT, 2200), 0x7FFF)


class FaultTest(unittest.TestCase):
    def test_reset_fault_is_a_power_on_reset(self):
        c, _ = chip_with(0.010, 12.0)
        wr(c, I.CONFIG, I.config_word(4, 1100, 1100), 0)
        wr(c, I.CALIBRATION, 2560, 0)
        c.inject("reset", now_us=100)
        self.assertEqual(rd(c, I.CONFIG, 100), 0x4127)
        self.assertEqual(rd(c, I.CALIBRATION, 100), 0)
        self.assertEqual(rd(c, I.CURRENT, 2300), 0)

    def test_stuck_freezes_results(self):
        c, inputs = chip_with(0.010, 12.0)
        c.advance(2200)
        c.inject("stuck")
        inputs.shunt_v = 0.020
        self.assertEqual(rd(c, I.SHUNT, 22000), 4000)
        c.clear()
        self.assertEqual(rd(c, I.SHUNT, 24200), 8000)

    def test_open_shunt_reads_no_current(self):
        c, _ = chip_with(0.010, 12.0)
        c.inject("open_shunt")
        self.assertEqual(rd(c, I.SHUNT, 2200), 0)
        self.assertEqual(rd(c, I.BUS, 2200), 9600)

    def test_gain_error_scales_the_shunt(self):
        c, _ = chip_with(0.010, 12.0)
        c.inject("gain", 1.5)
        self.assertEqual(rd(c, I.SHUNT, 2200), 6000)

    def test_noise_has_the_rms_asked_for(self):
        c, _ = chip_with(0.010, 12.0)
        c.inject("noise", 25e-6)  # 10 LSB rms
        vals = []
        for k in range(1, 401):
            vals.append(signed(rd(c, I.SHUNT, 2200 * k)))
        mean, rms = spread(vals)
        self.assertLess(abs(mean - 4000), 3)
        self.assertGreater(rms, 8)
        self.assertLess(rms, 12)

    def test_wrong_die_id(self):
        c, _ = chip_with()
        c.inject("die_id", 0x3220)
        self.assertEqual(rd(c, 0xFF, 0), 0x3220)
        self.assertEqual(rd(c, 0xFE, 0), 0x5449)

    def test_nack_and_stuck_low_are_told_to_the_bus(self):
        c, _ = chip_with()
        self.assertTrue(c.acks())
        self.assertFalse(c.holds_sda())
        c.inject("nack")
        c.inject("stuck_low")
        self.assertFalse(c.acks())
        self.assertTrue(c.holds_sda())
        c.clear()
        self.assertTrue(c.acks() and not c.holds_sda())

    def test_an_unknown_fault_is_refused(self):
        c, _ = chip_with()
        self.assertRaises(ValueError, c.inject, "melted")
