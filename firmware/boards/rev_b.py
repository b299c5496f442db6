"""dxboard rev B: Raspberry Pi Pico W (RP2040), ten high-side switches with status outputs, their
currents measured by four TI INA3221 triple monitors on I2C(0) (A0 to GND, VS, SDA, SCL:
0x40-0x43; 12 inputs, 10 used: 3 + 3 + 2 + 2) across 10 mOhm shunts, each input's CRITICAL
limit set to its channel's trip current (a fast trip input), the input voltage through a 1:11
divider on GPIO 26 (ADC0). The data ``firmware/main.py`` builds the board from."""

BOARD = {
    "name": "rev-b",
    "mcu": "rp2040",
    "channels": 10,
    "en_pins": (2, 3, 4, 5, 6, 7, 8, 9, 10, 11),
    "status_pins": (12, 13, 14, 15, 16, 17, 18, 19, 20, 21),
    "sense": {
        "chip": "ina3221",
        "i2c": {"id": 0, "sda": 0, "scl": 1, "freq": 400000, "timeout_us": 2000},
        "addrs": (0x40, 0x41, 0x42, 0x43),
        # per channel: (chip index into addrs, input 0-2 of that chip)
        "inputs": ((0, 0), (0, 1), (0, 2), (1, 0), (1, 1), (1, 2), (2, 0), (2, 1), (3, 0),
                   (3, 1)),
        "shunt_uohm": 10000,
    },
    "vin": {"adc_pin": 26, "divider": 11, "vref_mv": 3300},
}
