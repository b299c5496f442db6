"""The Modbus TCP register map of PROTOCOL.md §8, written once for the board and the host.

Zero-based protocol addresses. Channel k (k < ``MAX_CHANNELS``) has coil k (commanded
switch), discrete inputs k (read-back) and ``FAULT_INPUTS`` + k (any live fault), and input
registers ``CURRENT`` + k (mA, u16), ``STATE`` + k, ``LIVE_FAULTS`` + k, ``STICKY_FAULTS`` + k,
``TRIPS`` + k; the board's input registers follow at 100 (``INPUT_MV`` ... ``BOOT_ID``). The
holding table holds the configuration: the board's fields at ``BOARD_REGS`` (900-909), the
command register ``CMD_REG`` (990: write ``CMD_SAVE`` to save), and channel k's fields at
``CH_BASE`` + ``CH_STRIDE``·k + the offsets of ``CH_REGS`` (two registers for a u32, high
word first) and ``RETRY_OFF`` .. + ``RETRY_N`` for ``retry_ms`` (0 = unused). The field names
are those of ``protocol.settings``. The exception codes are Modbus's own.
"""

from protocol.compat import const

MAX_LEN = const(254)  # the MBAP length field's largest value
MAX_CHANNELS = const(16)

# discrete tables
COIL_SPAN = const(16)
DISCRETE_SPAN = const(32)
FAULT_INPUTS = const(16)

# input registers: per channel (add k), then the board
CURRENT = const(0)
STATE = const(16)
LIVE_FAULTS = const(32)
STICKY_FAULTS = const(48)
TRIPS = const(64)
INPUT_MV = const(100)
TOTAL_MA = const(101)  # u32, 101-102
UPTIME_MS = const(103)  # u32, 103-104
BOARD_FLAGS = const(105)
RESET_CAUSE = const(106)
CONFIG_STATUS = const(107)
CHANNEL_COUNT = const(108)
VERSION = const(109)
BOOT_ID = const(110)  # u32, 110-111: random at every boot (PROTOCOL.md section 2)
INPUT_SPAN = const(112)

# holding registers
HOLD_LO = const(900)
HOLD_HI = const(1512)  # exclusive
CH_BASE = const(1000)
CH_STRIDE = const(32)
CH_USED = const(22)  # offsets 0..21 of a channel's block are assigned
CMD_REG = const(990)
CMD_SAVE = const(1)
PROTECTED_OFF = const(15)  # read-only over Modbus

# channel field -> (offset, words); words 2 = u32 high word first
CH_REGS = (
    ("rated_ma", 0, 2), ("inrush_ms", 2, 1), ("inrush_factor_x10", 3, 1),
    ("trip_factor_x10", 4, 1), ("trip_samples", 5, 1), ("overload_start_x100", 6, 1),
    ("i2t_ms", 7, 1), ("short_retries", 8, 1), ("open_load_ma", 9, 1), ("open_load_ms", 10, 1),
    ("stuck_on_ma", 11, 1), ("stuck_on_ms", 12, 1), ("powerup", 13, 1), ("priority", 14, 1),
    ("protected", PROTECTED_OFF, 1), ("retry_reset_ms", 20, 2),
)
RETRY_OFF = const(16)
RETRY_N = const(4)
# board field -> (address, words)
BOARD_REGS = (
    ("total_limit_ma", 900, 2), ("uv_warn_mv", 902, 1), ("uv_shed_mv", 903, 1),
    ("uv_off_mv", 904, 1), ("uv_hyst_mv", 905, 1), ("tick_ms", 906, 1),
    ("powerup_spacing_ms", 907, 1), ("deadman_ms", 908, 2),
)
BOARD_REGS_END = const(910)

# exception codes
X_FUNCTION = const(1)  # unknown function, or writes not allowed for this client
X_ADDRESS = const(2)  # address out of range or not writable
X_VALUE = const(3)  # bad count or value
X_DEVICE = const(4)  # the board refused (latched, protected, switch fault, storage)


def is_assigned(addr: int) -> bool:
    """Whether a holding register address inside ``HOLD_LO..HOLD_HI`` carries a field."""
    if addr >= CH_BASE:
        return (addr - CH_BASE) % CH_STRIDE < CH_USED
    return HOLD_LO <= addr < BOARD_REGS_END or addr == CMD_REG
