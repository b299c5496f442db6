"""The INA3221 model against the numbers of TI's datasheet (SBOS576), not against our driver.

Runs under pytest and under the real MicroPython (``micropython tests/mpy_run.py
tests/emulator/parts``). Registers are read and written the way a bus master does.
"""

import unittest

from emulator.parts import ina3221 as T
from emulator.parts.ina3221 import Ina3221
from tests.emulator.parts.test_ina226 import Inputs, rd, signed, spread, wr


def chip_with(*chans):
    """A chip whose channel k sees ``chans[k] = (shunt_v, bus_v)``."""
    inputs = [Inputs(*c) for c in chans]
    while len(inputs) < 3:
        inputs.append(Inputs())
    return Ina3221(inputs), inputs


class PowerOnTest(unittest.TestCase):
    def test_power_on_values_and_ids(self):
        c, _ = chip_with()
        self.assertEqual(rd(c, 0x00, 0), 0x7127)
        for reg in (0x07, 0x08, 0x09, 0x0A, 0x0B, 0x0C):
            self.assertEqual(rd(c, reg, 0), 0x7FF8)
        self.assertEqual(rd(c, 0x0D, 0), 0)
        self.assertEqual(rd(c, 0x0E, 0), 0x7FFE)
        self.assertEqual(rd(c, 0x0F, 0), 0x0002)
        self.assertEqual(rd(c, 0x10, 0), 0x2710)
        self.assertEqual(rd(c, 0x11, 0), 0x2328)
        self.assertEqual(rd(c, 0xFE, 0), 0x5449)
        self.assertEqual(rd(c, 0xFF, 0), 0x3220)

    def test_power_on_config_decodes_as_the_datasheet_says(self):
        # 0x7127: all three channels, AVG 1, VBUSCT 1.1 ms, VSHCT 1.1 ms, continuous
        self.assertEqual(T.config_word(1, 1100, 1100), 0x7127)
        self.assertEqual(T.cycle_us(0x7127), 3 * 2200)

    def test_power_valid_limits_are_10_and_9_volts(self):
        self.assertEqual((0x2710 >> 3) * 8, 10000)
        self.assertEqual((0x2328 >> 3) * 8, 9000)

    def test_reset_bit_restores_every_register(self):
        c, _ = chip_with((0.010, 12.0))
        wr(c, 0x07, 0x1000, 0)
        wr(c, 0x0F, T.CEN | T.SCC1, 0)
        wr(c, 0x00, 0x8000, 100)
        self.assertEqual(rd(c, 0x00, 100), 0x7127)
        self.assertEqual(rd(c, 0x07, 100), 0x7FF8)
        self.assertEqual(rd(c, 0x0F, 100), 0x0002)
        self.assertEqual(rd(c, 0x01, 100), 0)


class ScaleTest(unittest.TestCase):
    def regs(self, shunt_v, bus_v=0.0):
        c, _ = chip_with((shunt_v, bus_v))
        return rd(c, 0x01, 6600), rd(c, 0x02, 6600)

    def test_shunt_is_40_uv_per_lsb_left_aligned_by_3(self):
        self.assertEqual(self.regs(0.010)[0], 250 << 3)  # 10 mV = 250 x 40 uV = 0x07D0
        self.assertEqual(self.regs(0.010)[0], 0x07D0)
        self.assertEqual(self.regs(-0.010)[0], 0xF830)
        self.assertEqual(self.regs(40e-6)[0], 0x0008)
        self.assertEqual(signed(self.regs(-40e-6)[0]), -8)

    def test_shunt_saturates_at_163_8_mv(self):
        self.assertEqual(self.regs(0.1638)[0], 0x7FF8)
        self.assertEqual(self.regs(0.500)[0], 0x7FF8)
        self.assertEqual(self.regs(-0.500)[0], 0x8000)

    def test_bus_is_8_mv_per_lsb_left_aligned_by_3(self):
        self.assertEqual(self.regs(0, 12.0)[1], 1500 << 3)  # 0x2EE0
        self.assertEqual(self.regs(0, 32.76)[1], 0x7FF8)
        self.assertEqual(self.regs(0, 40.0)[1], 0x7FF8)
        self.assertEqual(self.regs(0, -1.0)[1], 0)

    def test_each_channel_reads_its_own_pins(self):
        c, _ = chip_with((0.001, 5.0), (0.002, 12.0), (0.004, 24.0))
        self.assertEqual([rd(c, T.shunt_reg(ch), 6600) >> 3 for ch in range(3)], [25, 50, 100])
        self.assertEqual([rd(c, T.bus_reg(ch), 6600) >> 3 for ch in range(3)],
                         [625, 1500, 3000])

    def test_result_registers_are_read_only(self):
        c, _ = chip_with((0.010, 12.0))
        wr(c, 0x01, 0x1234, 6600)
        wr(c, 0x0D, 0x1234, 6600)
        self.assertEqual(rd(c, 0x01, 6600), 0x07D0)
        self.assertEqual(rd(c, 0x0D, 6600), 0)


class TimingTest(unittest.TestCase):
    def test_the_cycle_is_the_sum_over_enabled_channels_times_avg(self):
        cfg = T.config_word(4, 140, 588)  # what the driver chooses for the 10 ms tick
        self.assertEqual(T.cycle_us(cfg), 3 * (140 + 588) * 4)  # 8,736 us
        two = T.config_word(4, 140, 588, channels=3)
        self.assertEqual(T.cycle_us(two), 2 * 728 * 4)
        c, _ = chip_with((0.010, 12.0), (0.010, 12.0), (0.010, 12.0))
        wr(c, 0x00, cfg, 0)
        self.assertFalse(rd(c, 0x0F, 8735) & T.CVRF)
        self.assertEqual(rd(c, 0x05, 8735), 0)
        self.assertTrue(rd(c, 0x0F, 8736) & T.CVRF)
        self.assertEqual(rd(c, 0x05, 8736), 0x07D0)

    def test_a_disabled_channel_is_not_converted(self):
        c, _ = chip_with((0.010, 12.0), (0.010, 12.0), (0.010, 12.0))
        wr(c, 0x00, T.config_word(1, 140, 140, channels=5), 0)  # channels 1 and 3
        self.assertEqual(rd(c, 0x03, 560), 0)
        self.assertEqual(rd(c, 0x05, 560), 0x07D0)

    def test_shunt_only_mode(self):
        c, _ = chip_with((0.010, 12.0))
        cfg = T.config_word(4, 1100, 140, mode=5)
        self.assertEqual(T.cycle_us(cfg), 3 * 140 * 4)
        self.assertEqual(rd(c, 0x00, 0), 0x7127)
        wr(c, 0x00, cfg, 0)
        self.assertEqual(rd(c, 0x01, 1680), 0x07D0)
        self.assertEqual(rd(c, 0x02, 1680), 0)

    def test_averaging_is_a_real_average(self):
        # one channel, AVG 4 at 140 + 140 us: shunt conversions centred at 70, 350, 630, 910
        c, inputs = chip_with((0.0, 12.0))
        wr(c, 0x00, T.config_word(4, 140, 140, channels=1), 0)
        inputs[0].fn = lambda t: (0.020 if t < 280 else 0.0, 12.0)
        self.assertEqual(rd(c, 0x01, 1120) >> 3, 125)  # 500 / 4

    def test_triggered_mode_converts_once(self):
        c, inputs = chip_with((0.010, 12.0))
        wr(c, 0x00, T.config_word(1, 140, 140, mode=3, channels=1), 0)
        self.assertEqual(rd(c, 0x01, 280), 0x07D0)
        inputs[0].shunt_v = 0.020
        self.assertEqual(rd(c, 0x01, 10000), 0x07D0)


class AlertTest(unittest.TestCase):
    def test_critical_compares_every_conversion_not_the_average(self):
        # a 20 mV spike in one of four conversions: the average (5 mV) stays under a 10 mV
        # critical limit, the per-conversion comparison does not
        c, inputs = chip_with((0.0, 12.0))
        wr(c, 0x00, T.config_word(4, 140, 140, channels=1), 0)
        wr(c, T.critical_reg(0), 250 << 3, 0)
        wr(c, T.warning_reg(0), 250 << 3, 0)
        wr(c, 0x0F, T.CEN, 0)
        inputs[0].fn = lambda t: (0.020 if t < 280 else 0.0, 12.0)
        c.advance(1120)
        self.assertEqual(rd(c, 0x01, 1120) >> 3, 125)
        self.assertEqual(c.critical_pin(), 0)
        self.assertEqual(c.warning_pin(), 1)
        me = rd(c, 0x0F, 1120)
        self.assertTrue(me & T.CF1)
        self.assertFalse(me & T.WF1)
        self.assertEqual(c.critical_pin(), 1)  # latched (CEN): the read cleared it

    def test_critical_transparent_follows_the_conversions(self):
        c2 = chip_with((0.0, 0.0), (0.020, 12.0))[0]
        wr(c2, T.critical_reg(1), 250 << 3, 0)
        c2.advance(6600)
        self.assertTrue(c2.regs[0x0F] & (T.CF1 >> 1))
        c2.sources[1] = lambda t: (0.001, 12.0)
        c2.advance(13200)
        self.assertFalse(c2.regs[0x0F] & (T.CF1 >> 1))
        self.assertEqual(c2.critical_pin(), 1)

    def test_warning_on_the_average_latched_by_wen(self):
        c, inputs = chip_with((0.0, 12.0), (0.0, 12.0), (0.012, 12.0))
        wr(c, T.warning_reg(2), 250 << 3, 0)
        wr(c, 0x0F, T.WEN, 0)
        c.advance(6600)
        self.assertEqual(c.warning_pin(), 0)
        inputs[2].shunt_v = 0.0
        c.advance(13200)
        self.assertEqual(c.warning_pin(), 0)  # latched
        self.assertTrue(rd(c, 0x0F, 13200) & (T.WF1 >> 2))
        self.assertEqual(c.warning_pin(), 1)

    def test_shunt_sum_and_its_limit(self):
        c, _ = chip_with((0.004, 12.0), (0.006, 12.0), (0.010, 12.0))
        wr(c, 0x0F, T.SCC1 | (T.SCC1 >> 1), 0)  # channels 1 and 2 summed
        wr(c, 0x0E, 200 << 1, 0)
        self.assertEqual(rd(c, 0x0D, 6600), (100 + 150) << 1)
        self.assertTrue(rd(c, 0x0F, 6600) & T.SF)
        self.assertEqual(c.critical_pin(), 0)

    def test_power_valid(self):
        c, inputs = chip_with((0, 12.0), (0, 12.0), (0, 12.0))
        self.assertEqual(c.pv_pin(), 0)
        c.advance(6600)
        self.assertTrue(rd(c, 0x0F, 6600) & T.PVF)
        self.assertEqual(c.pv_pin(), 1)
        inputs[1].bus_v = 9.5  # between the limits: no change (hysteresis)
        c.advance(13200)
        self.assertEqual(c.pv_pin(), 1)
        inputs[1].bus_v = 8.0
        c.advance(19800)
        self.assertEqual(c.pv_pin(), 0)

    def test_cvrf_clears_on_read_and_flags_are_read_only(self):
        c, _ = chip_with((0.010, 12.0))
        self.assertTrue(rd(c, 0x0F, 6600) & T.CVRF)
        self.assertFalse(rd(c, 0x0F, 6601) & T.CVRF)
        wr(c, 0x0F, 0x03FF, 6601)
        self.assertEqual(rd(c, 0x0F, 6601) & 0x03FD, 0)


class FaultTest(unittest.TestCase):
    def test_reset_fault_is_a_power_on_reset(self):
        c, _ = chip_with((0.010, 12.0))
        wr(c, 0x00, T.config_word(4, 140, 588), 0)
        wr(c, T.critical_reg(0), 0x1000, 0)
        c.inject("reset", now_us=100)
        self.assertEqual(rd(c, 0x00, 100), 0x7127)
        self.assertEqual(rd(c, T.critical_reg(0), 100), 0x7FF8)

    def test_stuck_open_shunt_gain_and_noise(self):
        c, inputs = chip_with((0.010, 12.0))
        c.advance(6600)
        c.inject("stuck")
        inputs[0].shunt_v = 0.020
        self.assertEqual(rd(c, 0x01, 66000) >> 3, 250)
        c.clear()
        c.inject("open_shunt")
        self.assertEqual(rd(c, 0x01, 72600), 0)
        self.assertEqual(rd(c, 0x02, 72600) >> 3, 1500)
        c.clear()
        c.inject("gain", 0.5)
        self.assertEqual(rd(c, 0x01, 79200) >> 3, 250)
        c.clear()
        c.inject("noise", 400e-6)  # 10 LSB rms
        vals = [shunt for shunt in (signed(rd(c, 0x01, 79200 + 6600 * k)) >> 3
                                    for k in range(1, 301))]
        mean, rms = spread(vals)
        self.assertLess(abs(mean - 500), 3)
        self.assertGreater(rms, 8)
        self.assertLess(rms, 12)

    def test_wrong_die_nack_and_stuck_low(self):
        c, _ = chip_with()
        c.inject("die_id", 0x2260)
        self.assertEqual(rd(c, 0xFF, 0), 0x2260)
        c.inject("nack")
        c.inject("stuck_low")
        self.assertFalse(c.acks())
        self.assertTrue(c.holds_sda())
        c.clear()
        self.assertTrue(c.acks() and not c.holds_sda())
        self.assertEqual(rd(c, 0xFF, 0), 0x3220)
        self.assertRaises(ValueError, c.inject, "melted")
