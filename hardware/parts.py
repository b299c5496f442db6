"""The parts a builder orders, as data: manufacturer part numbers and the ratings the board's
limits are worked out from (``hardware/bom.py`` turns this and ``firmware/boards`` into each
revision's ``bom.csv`` and ``board.md``).

The revision files in ``firmware/boards`` say what the firmware needs (pins, sense chip,
addresses, shunt, divider); this module says what is bought around them: the microcontroller
module, each sense chip and the high-side switch it goes with, the shunt series (one part
number per power rating), the fuses, the input protection, the 5 V regulator, the connectors
and the passives.

The input protection is a surge stopper, not a TVS alone: a TVS that lets 26 V through clamps
a surge at about 42 V, above the INA3221's and the smart switch's absolute maxima (26 V,
28 V), so it protects nothing downstream. The LTC4364-2 (Analog Devices) instead drives a pass
MOSFET as a linear regulator during a surge, holding its output at a clamp its FB divider sets
(1.25 V x (1 + top / bottom), chosen per revision under the lowest absolute maximum behind
it), limits the current through a sense resistor (50 mV), turns the pass MOSFET off when a
surge or overcurrent outlasts its timer and retries (the -2 version), and drives a second
MOSFET as an ideal diode against a reversed battery; it runs from 4 V to 80 V and withstands
100 V, and -40 V at its input. A bidirectional TVS in front of it (standoff 28 V: neither the
highest input nor a reversed battery makes it conduct) clamps what would exceed the stopper's
and the MOSFETs' ratings, and holds a negative surge (``REVERSE_SURGES``) above -40 V.
``hardware/bom.py`` works the clamp's tolerance out and refuses a revision whose clamp could
reach a part's absolute maximum. The LTC4364's own support parts are in ``STOPPER``: the
capacitor on its TMR pin that sets how long it holds a surge or a short before it turns the
pass MOSFET off, the three-resistor string from the input to its UV and OV pins (it turns the
board off under about 6 V and refuses to start or retry above about 30 V), and the pull-up that
holds its SHDN pin high; ``bom.py`` works their time-outs and thresholds out and refuses a
revision whose UV threshold could reach its lowest input, whose OV threshold its highest
input, whose timer would run out before the bulk capacitor is charged, or (once the MOSFET's
SOA figure is here) whose pass MOSFET would take more than that allows. ``REVISIONS`` holds
what a revision chooses beyond its firmware file (which switch, the input fuse, the MCU
module); a revision without an entry gets its sense chip's defaults, so a new revision file is
enough for a first BOM. Every rating here is the datasheet's (the document is named beside it,
the LTC4364's pages by their addresses); nothing is measured. A figure the available pages do
not give is said to be so where it stands: "not confirmed against a datasheet" when a value is
used all the same, ``None`` (and "not checked" in ``board.md``) when it is not.
"""

from __future__ import annotations

from typing import Any

MCU: dict[str, dict[str, Any]] = {
    "rp2040": {
        "mfr": "Raspberry Pi", "mpn": "SC0918", "what": "Raspberry Pi Pico W (RP2040, 2 MB "
        "flash, CYW43439 Wi-Fi)", "short": "Pico W (RP2040)", "vsys_v": (1.8, 5.5),
        "adc_vref_v": 3.3, "adc_bits": 12, "adc_enob": 8.7, "io_vih_v": 2.0,
        "datasheet": "Raspberry Pi Pico W datasheet; RP2040 datasheet",
    },
}

# The module a revision's BOM orders for its MCU (``REVISIONS[rev]["module"]``; by default the
# MCU's own entry above). The Pico 2 W has the Pico W's footprint, pins and Wi-Fi chip, and
# MicroPython's ``RPI_PICO2_W`` build gives the firmware the same ``machine`` calls; its RP2350
# runs the tick in fewer instructions (ARMv8-M against ARMv6-M) at 150 MHz against 125
# (benchmarks/RESULTS.md, "The RP2040's own cycles per instruction"): the margin a revision
# whose tick on an RP2040 is under 1 ms only at the cycles measured wants. The limits in
# ``board.md`` stay worked out from the RP2040's figures (ADC, I/O), the part every test models; the
# RP2350's watchdog reaches 16,777 ms against the RP2040's 8,388, and the firmware asks for
# less. Order codes as the distributors list them (Mouser, DigiKey, TME: SC1633, Pico 2 W).
MODULES: dict[str, dict[str, Any]] = {
    "pico-2-w": {
        "mfr": "Raspberry Pi", "mpn": "SC1633", "what": "Raspberry Pi Pico 2 W (RP2350 at "
        "150 MHz, 4 MB flash, CYW43439 Wi-Fi; the Pico W's footprint and pins)",
        "short": "Pico 2 W (RP2350)",
        "datasheet": "Raspberry Pi Pico 2 W datasheet; RP2350 datasheet",
    },
}

# The sense chip of each revision (``BOARD["sense"]["chip"]``). ``fullscale_v`` is the shunt
# voltage at which the chip's reading saturates; ``bus_max_v`` the highest common-mode/bus
# voltage it measures; ``per_chip`` the channels one package serves; ``lsb_v`` one count of its
# shunt voltage reading.
SENSE: dict[str, dict[str, Any]] = {
    "ina226": {
        "mfr": "Texas Instruments", "mpn": "INA226AIDGSR", "what": "current/power monitor, "
        "I2C, 16 bit (VSSOP-10)", "per_chip": 1, "fullscale_v": 0.08192, "bus_max_v": 36.0,
        "abs_max_v": 40.0, "lsb_v": 2.5e-6, "switch": "tps1h100a", "datasheet": "TI SBOS547",
    },
    "ina3221": {
        "mfr": "Texas Instruments", "mpn": "INA3221AIRGVR", "what": "3-channel current/bus "
        "monitor, I2C, 13 bit (VQFN-16)", "per_chip": 3, "fullscale_v": 0.1638,
        "bus_max_v": 26.0, "abs_max_v": 26.0, "lsb_v": 40e-6, "switch": "tps1h100a",
        "datasheet": "TI SBOS576",
    },
    # a smart-switch board: the switch senses its own current (IS = I_L / k_ILIS into the
    # board's sense resistor, read by the MCU's ADC); no sense chip is bought. ``fullscale``
    # is worked out in bom.py from the revision's fault threshold on IS.
    "profet": {
        "mfr": "Infineon", "mpn": "BTS7008-2EPA", "what": "the switches' own current sense "
        "(IS), read by the MCU's ADC", "per_chip": 2, "bus_max_v": 28.0, "abs_max_v": 28.0,
        "switch": "bts7008", "datasheet": "Infineon BTS7008-2EPA data sheet rev. 1.20",
    },
}

# High-side switches. ``i_max_a``: the continuous current per channel the datasheet allows;
# ``limit_a``: the current limit the board sets (TPS1H100-Q1: R_CL = V_cl,th x K_CL / I_lim,
# datasheet equation 2, K_CL = 2000; the PROFET limits by itself: its overload detection
# current I_L(OVL), 40 A, as emulator/parts/profet.py models it). The PROFET's ``rds_on_ohm``
# (8 mOhm typical at 25 degC), ``k_ilis`` (I_L / I_IS, nominal) and ``i_is_fault_a`` (the
# current on IS for a fault, I_IS(FAULT) min and max) are its data sheet's.
SWITCHES: dict[str, dict[str, Any]] = {
    "tps1h100a": {
        "mfr": "Texas Instruments", "mpn": "TPS1H100AQPWPRQ1", "what": "smart high-side "
        "switch, 1 channel, 100 mOhm, adjustable current limit, version A (open-drain "
        "status) (HTSSOP-14)", "per_chip": 1, "i_max_a": 4.0, "limit_a": 5.0,
        "v_op": (5.0, 40.0), "abs_max_v": 48.0, "datasheet": "TI SLVSCM2",
    },
    "bts7008": {
        "mfr": "Infineon", "mpn": "BTS7008-2EPA", "what": "PROFET+2 12V smart high-side "
        "switch, 2 x 8 mOhm, analog current sense IS (k_ILIS 4785), DEN/DSEL "
        "(PG-TSDSO-14)", "per_chip": 2, "i_max_a": 7.5, "limit_a": 40.0,
        "rds_on_ohm": 0.008, "k_ilis": 4785, "i_is_fault_a": (4.4e-3, 10e-3),
        "v_op": (6.0, 18.0), "abs_max_v": 28.0,
        "datasheet": "Infineon BTS7008-2EPA data sheet rev. 1.20",
    },
}

# Vishay Power Metal Strip shunts, 1 %, by power rating at 70 degC (WSL/WSLP data sheets):
# the part number for a shunt of R milliohm is the pattern with R in Vishay's value code.
SHUNTS: tuple[tuple[float, str, str], ...] = (
    (0.25, "WSL1206R{code}FEA", "1206"),
    (0.5, "WSL2010R{code}FEA", "2010"),
    (1.0, "WSL2512R{code}FEA", "2512"),
    (3.0, "WSLP2512R{code}FEA", "2512"),
)
SHUNT_MARGIN = 2.0  # the shunt's rating is at least twice its I^2 R at the channel's limit

# Littelfuse ATO blade fuses (32 V), series 287: 0287 + the rating in amperes, three digits.
FUSE_SIZES_A: tuple[int, ...] = (1, 2, 3, 4, 5, 10, 15, 20, 25, 30)
FUSE_MARGIN = 1.25  # a fuse is rated at least 1.25 x the continuous current it carries
FUSE_MPN = "0287{amps:03d}.PXCN"
FUSE_V = 32.0  # the ATO series' voltage rating
FUSE_HOLDER = {"mfr": "Keystone Electronics", "mpn": "3557-2",
               "what": "PCB fuse holder for ATO blade fuses, 30 A"}

# The LTC4364's timer and its UV/OV comparators, from its data sheet (Linear Technology 436412f,
# LTC4364-1/LTC4364-2); only some of its pages were at hand, each named by its address:
#   p. 10 https://pdf.product.network/e1049276/analog.com/LTC4364CDE-1%23PBF.html ("Operation")
#   p. 12 http://38.142.81.21:8001/manual/linear-technology/dc2027a-a/datasheet-english/page-12.html
#   p. 16 http://38.142.81.21:8001/manual/linear-technology/dc2027a-a/datasheet-english/page-16.html
# - p. 10: in an overvoltage or an overcurrent a current source charges the capacitor on TMR;
#   in an overcurrent it is 5 times the overvoltage one; at 1.25 V FLT pulls low, at 1.35 V the
#   pass MOSFET turns off. The current limit is 50 mV over the sense resistor (SENSE to OUT),
#   25 mV while OUT is under 1.5 V (a shorted output).
# - p. 12: the -2 turns the pass MOSFET back on after the fault is gone and a cool-down period
#   has passed. OV (threshold 1.25 V, a divider from the input) holds HGATE low at power-up and,
#   once the MOSFET is on, does not turn it off but stops a restart after a fault while the
#   input is above it. UV detects an input undervoltage (a low battery).
# - p. 16: short-circuit stress P^2 t = (V_IN x dV_SNS / R_SNS)^2 x t_OC, t_OC the overcurrent
#   timer interval; its example (15 V, OUT 0 V, 25 mV, 12 mOhm, C_TMR 100 nF) gives 2.2 W^2 s,
#   "doubled to 4.4 W^2 s" for circuit tolerances. A capacitor from HGATE to ground may slow the
#   inrush at the expense of a slower turn-off (optional; its formula needs the HGATE pull-up
#   current, which was not found).
# Not found in those pages: the timer currents themselves (so t_OC is the p. 16 example's,
# scaled by the capacitance, at its 15 V across the MOSFET; how the currents change with that
# voltage is not known), the cool-down's length, the UV threshold (1.25 V: the datasheet's
# Figure 1 as read in https://electronics.stackexchange.com/questions/386403/ -- 383 k over
# 90.9 k + 10 k for 6 V), the UV/OV tolerance and hysteresis, the pin descriptions of SHDN,
# ENOUT and VCC, and the HGATE compensation paragraph.
LTC4364_TIMING: dict[str, Any] = {
    "short_sense_v": 0.025,  # p. 10: the current limit while OUT is under 1.5 V
    "tmr_flt_v": 1.25, "tmr_off_v": 1.35,  # p. 10: FLT low, then the pass MOSFET off
    "tmr_oc_ov_ratio": 5,  # p. 10: the timer charges 5 times faster in an overcurrent
    # p. 16's short-circuit example, from which t_OC per farad of C_TMR follows
    "tmr_example": {"v_in": 15.0, "sense_v": 0.025, "sense_ohm": 0.012, "tmr_f": 100e-9,
                    "p2t_w2s": 2.2},
    "p2t_margin": 2.0,  # p. 16: the P^2 t doubled for circuit tolerances
    "uv_ov_v": 1.25,  # p. 12 (OV); UV's the same: not confirmed against a datasheet
    "uv_ov_tol": 0.02,  # not found: the FB reference's 2 %, not confirmed against a datasheet
    "cooldown_s": None,  # p. 12: the -2 retries after a cool-down; its length not found
}

INPUT: dict[str, dict[str, Any]] = {
    # ``vbr_max_v``: breakdown at its highest; ``clamp_v`` at ``ipp_a`` (10/1000 us): between
    # the two the clamp rises about linearly with the current (``bom.reverse_surge``)
    "tvs": {"mfr": "Littelfuse", "mpn": "SMCJ28CA", "what": "TVS diode 1500 W, "
            "bidirectional, standoff 28 V, breakdown 31.1 V to 34.4 V, clamp 45.4 V at 33.0 A "
            "(DO-214AB), in front of the surge stopper", "standoff_v": 28.0, "vbr_max_v": 34.4,
            "clamp_v": 45.4, "ipp_a": 33.0, "datasheet": "Littelfuse SMCJ series data sheet"},
    "surge_stopper": {"mfr": "Analog Devices", "mpn": "LTC4364IMS-2#PBF", "what": "surge "
                      "stopper with ideal diode: output clamp set by a divider on FB "
                      "(1.25 V), 50 mV current limit, fault timer with auto-retry, reverse "
                      "input to -40 V; 4 V to 80 V, 100 V absolute (MSOP-16)",
                      "v_op": (4.0, 80.0), "abs_max_v": 100.0, "reverse_v": 40.0,
                      "fb_v": 1.25, "fb_tol": 0.02,
                      "sense_v": 0.050, **LTC4364_TIMING,
                      "datasheet": "Analog Devices LTC4364 data sheet"},
    # ``soa_p2t_w2s``: the P^2 t its safe operating area allows for a pulse of a few ms (the
    # LTC4364 data sheet compares the pass MOSFET's stress with it, page 16); its SOA figure
    # was not found: None, and board.md says the stress is not checked
    "mosfet": {"mfr": "Texas Instruments", "mpn": "CSD18540Q5B", "what": "N-channel MOSFET "
               "60 V, 1.8 mOhm at VGS 10 V (SON 5x6): Q1 the LTC4364's pass device (HGATE), "
               "Q2 its ideal diode against a reversed battery (DGATE)", "rds_on_ohm": 0.0018,
               "abs_max_v": 60.0, "soa_p2t_w2s": None, "datasheet": "TI SLPS412"},
    "regulator": {"mfr": "RECOM", "mpn": "R-78E5.0-0.5", "what": "5 V 0.5 A switching "
                  "regulator, input 7 V to 28 V (SIP-3), feeds the Pico's VSYS",
                  "v_in": (7.0, 28.0), "abs_max_v": 28.0},
    "bulk": {"mfr": "Panasonic", "mpn": "EEU-FR1V471", "what": "470 uF 35 V electrolytic, "
             "input bulk capacitor, after the surge stopper", "abs_max_v": 35.0,
             "farad": 470e-6},
}
CLAMP_BOTTOM_OHM = 10000  # the FB divider's lower resistor; the upper one is per revision
RESISTOR_TOL = 0.001  # the 0.1 % thin-film resistors of the FB divider
# Yageo RT0603 0.1 %: the part number of a value in kOhm (E96)
CLAMP_MPN = "RT0603BRD07{kohm}KL"
CURRENT_LIMIT_MARGIN = 1.25  # the surge stopper limits at 1.25 x the input fuse's rating

# The LTC4364's support parts (U3), one set for every revision; ``bom.stopper`` works out what
# they set and checks it against each revision's input range.
# - ``timer``: TMR to ground. 100 nF is the data sheet's own example (p. 16), so its time-outs
#   are the example's; X7R, +-10 % (K) and up to +-15 % over temperature.
# - ``uv_top``/``uv_mid``/``uv_bottom``: one string from the input (VCC's side of Q1) to ground,
#   UV at the top joint, OV at the lower one, as the data sheet's Figure 1 draws it:
#   UV = 1.25 V x (top + mid + bottom) / (mid + bottom), about 6.0 V, under the regulator's 7 V
#   minimum so that it never cuts inside the input range (the firmware's uv_off acts above);
#   OV = 1.25 V x (top + mid + bottom) / bottom, about 30 V, above every revision's highest
#   input. 241 kOhm in all: 0.11 mA from the battery at 26 V, whenever it is connected.
# - ``shdn_pullup``: SHDN to VCC, so the chip is always on; SHDN's input current and rating were
#   not found: a resistor keeps it high whatever pull-down or clamp it has (0.45 mA at most into
#   one, at the TVS's 45.4 V).
# FLT (pulls low before a turn-off, p. 10) and ENOUT (its description not found) are left
# open: the firmware reads neither. No HGATE capacitor (optional, p. 16): the inrush is held
# by the current limit, and ``bom.stopper`` checks that the timer outlasts it.
STOPPER: dict[str, dict[str, Any]] = {
    "timer": {"ref": "CT1", "mfr": "Murata", "mpn": "GRM188R71H104KA93D", "farad": 100e-9,
              "tol": 0.10, "tempco": 0.15, "what": "100 nF 50 V X7R 0603: the surge stopper's "
              "fault timer (TMR to ground)"},
    "uv_top": {"ref": "RUV1", "mfr": "Yageo", "mpn": "RC0603FR-07191KL", "ohm": 191000,
               "what": "191 kOhm 1 % 0603: the surge stopper's UV/OV string, top (input to UV)"},
    "uv_mid": {"ref": "RUV2", "mfr": "Yageo", "mpn": "RC0603FR-0740K2L", "ohm": 40200,
               "what": "40.2 kOhm 1 % 0603: the surge stopper's UV/OV string, middle (UV to OV)"},
    "uv_bottom": {"ref": "RUV3", "mfr": "Yageo", "mpn": "RC0603FR-0710KL", "ohm": 10000,
                  "what": "10 kOhm 1 % 0603: the surge stopper's UV/OV string, bottom (OV to "
                  "ground)"},
    "shdn_pullup": {"ref": "REN1", "mfr": "Yageo", "mpn": "RC0603FR-07100KL", "ohm": 100000,
                    "what": "100 kOhm 1 % 0603: the surge stopper's SHDN pulled up to its VCC "
                    "(always on)"},
}
UV_OV_RES_TOL = 0.01  # the 1 % resistors of the UV/OV string
START_MARGIN = 1.5  # the overcurrent time-out, at its shortest, outlasts 1.5 x the bulk charge

CONNECTORS: dict[str, dict[str, Any]] = {
    "input": {"mfr": "AMASS", "mpn": "XT60PW-M", "what": "XT60 male, PCB, right angle: the "
              "battery input", "rating_a": 30.0},
    "output_header": {"mfr": "Phoenix Contact", "mpn": "1757242", "what": "MSTBA 2,5/ 2-G-5,08"
                      " header, 2 pins, 12 A: one per channel output", "rating_a": 12.0},
    "output_plug": {"mfr": "Phoenix Contact", "mpn": "1757019", "what": "MSTB 2,5/ 2-ST-5,08 "
                    "plug, 2 positions, 12 A: the load's cable", "rating_a": 12.0},
}

PASSIVES: dict[str, dict[str, Any]] = {
    "i2c_pullup": {"mfr": "Yageo", "mpn": "RC0603FR-072K2L", "what": "2.2 kOhm 1 % 0603: "
                   "SDA and SCL pull-up to 3.3 V"},
    "divider_top": {"mfr": "Yageo", "mpn": "RT0603BRD07100KL", "what": "100 kOhm 0.1 % 0603: "
                    "input divider, top"},
    "divider_bottom": {"mfr": "Yageo", "mpn": "RT0603BRD0710KL", "what": "10 kOhm 0.1 % 0603: "
                       "input divider, bottom (1:11 with the 100 kOhm)"},
    "readback_series": {"mfr": "Yageo", "mpn": "RC0603FR-07100KL", "what": "100 kOhm 1 % "
                        "0603: output read-back divider, top", "ohm": 100000},
    "readback_pulldown": {"mfr": "Yageo", "mpn": "RC0603FR-0756KL", "what": "56 kOhm 1 % 0603:"
                          " output read-back divider, to ground", "ohm": 56000},
    "readback_clamp": {"mfr": "Nexperia", "mpn": "BAT54S,215", "what": "dual Schottky in "
                       "series (SOT-23): clamps the read-back between ground and 3.3 V"},
    "is_top": {"mfr": "Yageo", "mpn": "RT1206BRD07909RL", "what": "909 Ohm 0.1 % 1206 0.25 W:"
               " the IS sense node to ground, upper leg (the revision's 900 Ohm, nearest E96 "
               "value; only the lower leg sets the reading)", "watts": 0.25},
    "is_adc": {"mfr": "Yageo", "mpn": "RT0603BRD07300RL", "what": "300 Ohm 0.1 % 0603: the "
               "IS sense node to ground, lower leg, read by the ADC", "watts": 0.1},
    "bypass": {"mfr": "Murata", "mpn": "GRM188R71H104KA93D", "what": "100 nF 50 V X7R 0603: "
               "one per IC supply pin, one at the ADC pin"},
}

# The negative surges the input must stand: ISO 7637-2 test pulse 1 (an inductive load switched
# off beside the board: the battery line swings below ground), its highest levels, as (name,
# open-circuit volts, source ohms). The TVS takes the current; the surge stopper's input must
# stay above -``reverse_v`` (its ideal-diode MOSFET blocks the rest).
REVERSE_SURGES: tuple[tuple[str, float, float], ...] = (
    ("ISO 7637-2 pulse 1, 12 V system (-150 V, 10 Ohm, 2 ms)", 150.0, 10.0),
    ("ISO 7637-2 pulse 1, 24 V system (-600 V, 50 Ohm, 1 ms)", 600.0, 50.0),
)

# What a revision chooses beyond its firmware file; missing keys: the sense chip's defaults.
# ``clamp_top_kohm``: the FB divider's upper resistor (E96), which sets the surge stopper's clamp
# (rev A 26.9 V under the regulator's 28 V; rev B 24.6 V under the INA3221's 26 V; rev C 20.0 V,
# just above the BTS7008's 18 V operating range, far under its 28 V).
REVISIONS: dict[str, dict[str, Any]] = {
    "rev-a": {"switch": "tps1h100a", "input_fuse_a": 20, "clamp_top_kohm": 205},
    # rev B's and rev C's ticks: 0.72-0.75 and 0.86-0.89 ms of CPU on an RP2040 at its measured
    # cycles per instruction, 0.35-0.62 and 0.44-0.77 ms on an RP2350 (hardware/README.md)
    "rev-b": {"switch": "tps1h100a", "input_fuse_a": 20, "clamp_top_kohm": 187,
              "module": "pico-2-w"},
    "rev-c": {"switch": "bts7008", "input_fuse_a": 20, "clamp_top_kohm": 150,
              "module": "pico-2-w"},
}
DEFAULT_INPUT_FUSE_A = 20
DEFAULT_CLAMP_TOP_KOHM = 187  # 24.6 V: under every part's absolute maximum here but the INA3221's
I2C_RISE_NS = 300  # fast mode (400 kHz): SDA/SCL rise time at most 300 ns (I2C-bus spec UM10204)
I2C_PIN_PF = 10  # input capacitance per chip on the bus, pF (INA226: 3 pF typ; generous)
I2C_TRACE_PF = 50  # the bus's copper and the Pico's pins, pF


class PartsError(Exception):
    """A revision names a part this catalogue does not have: the message says what to add."""


def chip(board: dict[str, Any]) -> dict[str, Any]:
    name = board["sense"]["chip"]
    if name not in SENSE:
        raise PartsError(f"hardware/parts.py: {board['name']} senses with {name!r}, which SENSE "
                         f"does not list; add it to SENSE (one of: {', '.join(sorted(SENSE))})")
    return SENSE[name]


def choices(board: dict[str, Any]) -> dict[str, Any]:
    """The revision's choices: its ``REVISIONS`` entry over its sense chip's defaults."""
    got = {"switch": chip(board)["switch"], "input_fuse_a": DEFAULT_INPUT_FUSE_A,
           "clamp_top_kohm": DEFAULT_CLAMP_TOP_KOHM}
    got.update(REVISIONS.get(board["name"], {}))
    if got["switch"] not in SWITCHES:
        raise PartsError(f"hardware/parts.py: {board['name']} uses switch {got['switch']!r}, "
                         f"which SWITCHES does not list; add it there")
    module(board)  # the MCU and the module it orders are listed
    return got


def module(board: dict[str, Any]) -> dict[str, Any]:
    """What the revision's BOM orders for its MCU: its ``module`` choice in ``REVISIONS``, else
    the MCU's entry (manufacturer, part number, description, ``short`` name). It needs nothing
    else of the revision (``pinmap.py`` names it on a revision ``SENSE`` does not know yet)."""
    if board["mcu"] not in MCU:
        raise PartsError(f"hardware/parts.py: {board['name']} runs on {board['mcu']!r}, which "
                         "MCU does not list; add it there")
    name = REVISIONS.get(board["name"], {}).get("module")
    if name is None:
        return MCU[board["mcu"]]
    if name not in MODULES:
        raise PartsError(f"hardware/parts.py: {board['name']} orders module {name!r}, which "
                         "MODULES does not list; add it there")
    return MODULES[name]


def fuse_for(amps: float) -> int:
    """The smallest fuse size of at least ``FUSE_MARGIN`` x ``amps``."""
    for size in FUSE_SIZES_A:
        if size >= amps * FUSE_MARGIN:
            return size
    raise PartsError(f"hardware/parts.py: no fuse in FUSE_SIZES_A carries {amps:g} A "
                     f"x {FUSE_MARGIN}; add a larger size")


def shunt_for(ohm: float, amps: float) -> tuple[float, str, str]:
    """(rating W, part number, package) of the smallest shunt rated for ``SHUNT_MARGIN`` x
    I^2 R at ``amps``."""
    need = amps * amps * ohm * SHUNT_MARGIN
    code = f"{ohm:.4f}"[2:]  # 0.0100 -> "0100": Vishay's code for 10 mOhm
    for watts, pattern, package in SHUNTS:
        if watts >= need:
            return watts, pattern.format(code=code), package
    raise PartsError(f"hardware/parts.py: no shunt in SHUNTS is rated for {need:.2f} W; add "
                     "a larger one")
