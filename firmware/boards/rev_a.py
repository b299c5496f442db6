"""dxboard rev A: Raspberry Pi Pico W (RP2040), ten high-side switches with status outputs, ten
TI INA226 monitors on I2C(0) across 10 mOhm shunts, the input voltage through a 1:11 divider on
GPIO 26 (ADC0). The data ``firmware/main.py`` builds the board from."""

BOARD = {
    "name": "rev-a",
    "mcu": "rp2040",
    "channels": 10,
    "en_pins": (2, 3, 4, 5, 6, 7, 8, 9, 10, 11),
    "status_pins": (12, 13, 14, 15, 16, 17, 18, 19, 20, 21),
    "sense": {
        "chip": "ina226",
        "i2c": {"id": 0, "sda": 0, "scl": 1, "freq": 400000, "timeout_us": 2000},
        "addrs": (0x40, 0x41, 0x42, 0x43, 0x44, 0x45, 0x46, 0x47, 0x48, 0x49),
        "shunt_uohm": 10000,
    },
    "vin": {"adc_pin": 26, "divider": 11, "vref_mv": 3300},
}
