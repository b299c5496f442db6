"""dxboard rev C: Raspberry Pi Pico W (RP2040), ten channels on five Infineon BTS7008-2EPA dual
smart high-side switches (PROFET+2 12V, two channels a part, each with its own protection and
analog current sense). No I2C: every part's IS pin joins one sense node to ground through
R_IS = 1.2 kOhm (900 + 300 Ohm), the RP2040's ADC1 (GPIO 27) tapping the 300 Ohm leg; one DEN
pin a part picks the part on the node, one shared DSEL pin the channel (the RP2040 has three
ADC inputs: one for the sense node, one for the input voltage, one spare). IN0/IN1 of part d
are channels 2d and 2d + 1's enable pins; the outputs have no status pins (the switch reports
through IS). The input voltage through a 1:11 divider on GPIO 26 (ADC0). The data
``firmware/main.py`` builds the board from (``firmware.hal.profet`` reads it)."""

BOARD = {
    "name": "rev-c",
    "mcu": "rp2040",
    "channels": 10,
    "en_pins": (2, 3, 4, 5, 6, 7, 8, 9, 10, 11),
    "status_pins": (),
    "sense": {
        "chip": "profet",
        "part": "BTS7008-2EPA",
        "den_pins": (12, 13, 14, 15, 16),
        "dsel_pin": 17,
        "is_adc_pin": 27,
        "k_ilis": 4785,  # I_L / I_IS, nominal
        "r_is_ohm": 1200,  # IS to ground in all (>= 820 Ohm)
        "r_adc_ohm": 300,  # the lower leg the ADC reads
        "vref_mv": 3300,
        "settle_us": 20,  # t_sIS after DEN or DSEL changes
        "accurate_ma": 100,  # below: low, not measured (kILIS band wider than +-30 %)
        "fault_ua": 3800,  # I_IS(FAULT) is 4.4-10 mA, I_IS(OLOFF) 1.9-3.5 mA
        "oloff_ua": 1500,
    },
    "vin": {"adc_pin": 26, "divider": 11, "vref_mv": 3300},
}
