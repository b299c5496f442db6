"""Board revisions as data: one module per revision, one firmware.

Each revision is a small module here (``rev_a.py`` for "rev-a") holding one dict, ``BOARD``: the
microcontroller, the switches' enable and status pins, the current sensing (chip, bus, addresses,
shunt) and the input voltage divider. ``firmware/main.py`` builds its HAL from it
(``firmware.hal.target.build``), so adding a revision is a file, not code. ``load(name)`` returns
a revision's description; without a name, the one named by the file ``board_rev`` on the board's
flash (one line, written when the board is flashed), else ``DEFAULT``.

Keys: ``name``, ``mcu``, ``channels`` (n), ``en_pins`` and ``status_pins`` (n GPIOs each),
``sense`` = {``chip``: "ina226", ``i2c``: {``id``, ``scl``, ``sda``, ``freq``, ``timeout_us``},
``addrs`` (n 7-bit addresses), ``shunt_uohm``}; an INA3221 board (``chip``: "ina3221") names
its chips in ``addrs`` and adds ``inputs`` (per channel: the chip's index in ``addrs`` and its
input 0-2); a smart-switch board (``chip``: "profet") has no I2C: see ``rev_c.py``. ``vin`` =
{``adc_pin``, ``divider``: the ratio of the input divider (the ADC sees input / divider),
``vref_mv``}.
"""

if False:  # typing only; MicroPython never imports typing (the block is compiled away)
    from typing import Any

    Revision = dict[str, Any]  # a revision's ``BOARD``: nested plain data, as the keys above

DEFAULT = "rev-a"
SELECTED = "board_rev"


def selected() -> str:
    """The revision this board was flashed as (the ``board_rev`` file), else ``DEFAULT``."""
    try:
        with open(SELECTED) as f:
            name = f.read().strip()
    except OSError:
        return DEFAULT
    return name or DEFAULT


def known() -> "list[str]":
    """The revisions this firmware has: one ``rev_x.py`` (or ``.mpy``) file each here."""
    try:
        import os

        names = os.listdir(__file__.rsplit("/", 1)[0])
    except (OSError, NameError, AttributeError):
        return [DEFAULT]
    out = []
    for n in names:
        if n.startswith("rev_") and (n.endswith(".py") or n.endswith(".mpy")):
            out.append("rev-" + n[4:n.rindex(".")])
    return sorted(out)


def load(name: str = "") -> "Revision":
    """A revision's description; ``ValueError`` naming the revisions if there is none."""
    name = name or selected()
    mod = "rev_" + name[4:] if name.startswith("rev-") else ""
    try:
        module = __import__("firmware.boards." + mod, None, None, ["BOARD"])
    except ImportError:
        raise ValueError("no board revision " + repr(name) + ": " + ", ".join(known())) from None
    board: "Revision" = module.BOARD
    return board


def mv_per_count_x1000(vin: "dict[str, Any]") -> int:
    """The input voltage per count of ``read_u16`` (16 bit full scale = vref), in mV x 1000."""
    return int(vin["vref_mv"] * vin["divider"] * 1000 // 65535)
