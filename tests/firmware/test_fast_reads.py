"""The HAL's per-tick reads in ``firmware.fast`` (viper on the board) against the drivers' own
Python, value by value over the whole range of what a chip or the ADC can hand back, the edges
of every threshold included: ``ina3221_read`` (through ``Ina3221Bank.read``) against
``ChipBank.read``, ``profet_read`` (through ``ProfetBank.read``) against its loop in Python.
Fakes of the bus, the pins and the ADC; both interpreters (MicroPython runs the viper code
itself; CPython the same source as plain Python). The part models and their faults are
``tests/emulator/parts``'s.
"""

import unittest

from firmware import fast, hal
from firmware.hal.chipbank import ChipBank
from firmware.hal.ina3221 import Ina3221Bank
from firmware.hal.profet import ProfetBank


class Bus:
    """An I2C bus of INA3221s that answers every register from ``regs[(addr, reg)]`` (IDs
    and CONFIG as the driver wants them) and counts the transactions."""

    def __init__(self, bank_configs):
        self.regs = {}
        self.n = 0
        for addr, config in bank_configs:
            self.regs[(addr, 0xFE)] = 0x5449
            self.regs[(addr, 0xFF)] = 0x3220
            self.regs[(addr, 0x00)] = config

    def readfrom_mem_into(self, addr, reg, buf):
        self.n += 1
        v = self.regs.get((addr, reg), 0)
        buf[0] = v >> 8
        buf[1] = v & 0xFF

    def writeto_mem(self, addr, reg, buf):
        self.n += 1
        if reg == 0x00:
            self.regs[(addr, 0)] = (buf[0] << 8) | buf[1]


INPUTS = ((0, 0), (0, 1), (0, 2), (1, 0), (1, 1), (1, 2), (2, 0), (2, 1), (3, 0), (3, 1))
ADDRS = (0x40, 0x41, 0x42, 0x43)


def ina3221(shunt_uohm):
    from firmware.hal.ina3221 import config_for

    used = [0, 0, 0, 0]
    for c, k in INPUTS:
        used[c] |= 1 << k
    bus = Bus([(ADDRS[i], config_for(used[i])) for i in range(4)])
    bank = Ina3221Bank(bus, ADDRS, INPUTS, shunt_uohm)
    bank.setup()
    return bus, bank


class Ina3221ReadTest(unittest.TestCase):
    def sweep(self, shunt_uohm):
        """Every SHUNT word a step apart (both signs, the full scale) and the CRITICAL flags in
        every pattern, on ten channels a read: the fast read and ``ChipBank.read`` agree."""
        bus, bank = ina3221(shunt_uohm)
        rbus, ref = ina3221(shunt_uohm)
        words = list(range(0, 0x10000, 37)) + [0x7FF8, 0x7FFF, 0x8000, 0xFFF8, 0xFFFF, 8, 0]
        out = [0] * 10
        want = [0] * 10
        i = 0
        while i < len(words):
            for ch in range(10):
                c, k = INPUTS[ch]
                w = words[(i + ch) % len(words)]
                bus.regs[(ADDRS[c], 1 + 2 * k)] = rbus.regs[(ADDRS[c], 1 + 2 * k)] = w
            for c in range(4):  # the flags: a pattern per read
                flags = ((i // 10 + c) % 8) << 7
                bus.regs[(ADDRS[c], 0x0F)] = rbus.regs[(ADDRS[c], 0x0F)] = 0x0400 | flags
            bank.read(out)
            ChipBank.read(ref, want)
            self.assertEqual(out, want, "words from %d" % i)
            self.assertEqual(list(bank.flags), list(ref.flags))
            self.assertEqual(bank.trips, ref.trips)
            self.assertEqual(bus.n, rbus.n)
            i += 10
        self.assertGreater(ref.trips, 100)
        return ref

    def test_every_shunt_word_and_flag_as_chipbank_reads_it(self):
        self.sweep(10000)

    def test_a_small_shunt_the_largest_product(self):
        # 1 mOhm: 4095 counts x 40000 / 1000 = 163,800 mA; 4095 x 40000 < 2^28
        self.sweep(1000)


class Pin:
    OUT = 1

    def __init__(self, pin_id, mode=-1, value=0):
        self.id = pin_id
        self.level = value
        self.log = None

    def value(self, v=None):
        if v is None:
            return self.level
        self.level = v
        if self.log is not None:
            self.log.append((self.id, v))
        return None


class Adc:
    def __init__(self, pin):
        self.words = []

    def read_u16(self):
        return self.words.pop(0)


class Machine:
    Pin = Pin

    def ADC(self, pin):
        return Adc(pin)


REV_C = {"den_pins": (12, 13, 14, 15, 16), "dsel_pin": 17, "is_adc_pin": 27, "k_ilis": 4785,
         "r_adc_ohm": 300, "vref_mv": 3300, "settle_us": 20, "accurate_ma": 100,
         "fault_ua": 3800, "oloff_ua": 1500}


def profet(sense):
    log = []
    bank = ProfetBank(sense, Machine(), lambda us: log.append(("wait", us)))
    bank.wire([Pin(2 + ch) for ch in range(bank.n)])
    for p in bank.den + [bank.dsel]:
        p.log = log
    return bank, log


class ProfetReadTest(unittest.TestCase):
    def sweep(self, sense, fast_read=True):
        """Every sum of two conversions (0 to 8190: the thresholds' edges among them), the
        channel on and off, the 12-bit words as the ADC scales them to 16 bits: the fast read
        and the loop in Python agree, pin for pin and wait for wait."""
        bank, log = profet(sense)
        ref, rlog = profet(sense)
        self.assertEqual(bank.fast, fast_read)
        ref.fast = False
        out = [0] * 10
        want = [0] * 10
        s = 0
        seen = set()
        while s <= 8190:
            words = []
            for ch in range(10):
                t = s + ch if s + ch <= 8190 else 8190
                a = t // 2
                for v in (a, t - a):
                    words.append((v << 4) | (v >> 8))
                on = (s // 10 + ch) % 3 != 0
                bank.switches[ch].level = ref.switches[ch].level = 1 if on else 0
            bank.adc.words = words[:]
            ref.adc.words = words
            del log[:]
            del rlog[:]
            bank.read(out)
            ref.read(want)
            self.assertEqual(out, want, "sums from %d" % s)
            self.assertEqual(bank.open_off, ref.open_off)
            self.assertEqual(bank.faults, ref.faults)
            self.assertEqual(log, rlog)
            self.assertEqual(bank.adc.words, [])
            for v in out:
                seen.add(v if v <= 0 else 1)
            s += 10
        return bank, seen

    def test_rev_c_every_sum_as_the_python_loop(self):
        seen = self.sweep(REV_C)[1]
        self.assertEqual(seen, {hal.TRIPPED, hal.LOW, 0, 1})  # (1: a current)

    def test_thresholds_met_exactly(self):
        # vref / (2 x 4095 x r_adc) = 1: the IS current in uA is the sum itself, so the sweep
        # lands on fault_ua, oloff_ua and (x k_ilis / 1000) accurate_ma exactly
        sense = dict(REV_C)
        sense["vref_mv"] = 8190
        sense["r_adc_ohm"] = 1000
        sense["k_ilis"] = 5000
        bank, seen = self.sweep(sense)
        self.assertEqual(list(bank.par)[1:3], [1, 1])
        self.assertEqual(seen, {hal.TRIPPED, hal.LOW, 0, 1})

    def test_a_fraction_that_would_overflow_takes_the_python_loop(self):
        sense = dict(REV_C)
        sense["vref_mv"] = 300000  # 300,000,000 / 8190 = 10,000,000 / 273: x 8190 > 2^31
        sense["r_adc_ohm"] = 1
        self.assertEqual(self.sweep(sense, fast_read=False)[1], {hal.TRIPPED, 0})

    def test_the_codes_are_firmware_hals(self):
        self.assertEqual(fast.C_TRIPPED, hal.TRIPPED)
        self.assertEqual(fast.C_LOW, hal.LOW)
