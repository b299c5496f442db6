"""Numbers of the dxboard protocol that firmware, emulator and host share.

Everything here is normative and documented in ``protocol/PROTOCOL.md``: channel states,
fault flags, event kinds, reset causes, configuration status, capabilities and error codes.
Change a value only together with PROTOCOL.md and a protocol version bump.
"""

from protocol.compat import const

PROTOCOL_VERSION = const(1)
BOARD_CHANNEL = const(0xFF)  # "channel" number meaning the board itself

# --- channel state machine states (u8) -------------------------------------------------
ST_OFF = const(0)  # switched off (commanded off, or never on)
ST_INRUSH = const(1)  # just switched on: inrush window, raised limit
ST_ON = const(2)  # on and within limits
ST_TRIPPED = const(3)  # switched off by protection, waiting to retry
ST_LATCHED = const(4)  # tripped too often: off until an explicit clear
ST_FAULTED = const(5)  # the switch itself is faulty (stuck on / stuck off)
STATE_NAMES = ("off", "inrush", "on", "tripped", "latched", "faulted")

# --- fault flags (u16 bit mask), live and sticky ---------------------------------------
F_SHORT = const(0x0001)  # instant trip: >= trip_factor x rated for trip_samples samples
F_OVERLOAD = const(0x0002)  # I^2t thermal model reached its limit
F_INRUSH = const(0x0004)  # above inrush_factor x rated inside the inrush window
F_OPEN_LOAD = const(0x0008)  # warning: on but drawing almost nothing
F_STUCK_ON = const(0x0010)  # switched off but current still flows
F_STUCK_OFF = const(0x0020)  # commanded on but the switch reads back off
F_SHED_TOTAL = const(0x0040)  # switched off to keep the board under its total limit
F_SHED_UV = const(0x0080)  # switched off by input under-voltage
F_DEADMAN = const(0x0100)  # set to the safe state by the host dead-man timeout
F_SENSOR = const(0x0200)  # the current sensor reads current while the switch reads back open
F_LOW = const(0x0400)  # not a fault: below the sensing part's accurate range, low, not measured
NOT_FAULTS = F_LOW  # live flags that say how a reading was made, not that anything is wrong
FAULT_NAMES = (
    "short",
    "overload",
    "inrush",
    "open_load",
    "stuck_on",
    "stuck_off",
    "shed_total",
    "shed_uv",
    "deadman",
    "sensor",
    "low",
)

# --- board flags (u16 bit mask) ---------------------------------------------------------
B_UV_WARN = const(0x0001)  # input voltage below the warning threshold
B_UV_SHED = const(0x0002)  # below the shed threshold: non-protected channels shed
B_UV_OFF = const(0x0004)  # below the off threshold: everything off
B_OVER_TOTAL = const(0x0008)  # total current above the board limit
B_SAFE_MODE = const(0x0010)  # booted in safe mode (watchdog reset loop)
B_DEADMAN = const(0x0020)  # host dead-man timeout expired
BOARD_FLAG_NAMES = ("uv_warn", "uv_shed", "uv_off", "over_total", "safe_mode", "deadman")

# --- event kinds (u8) -----------------------------------------------------------------
EV_TRIP = const(1)  # a channel tripped (faults say why)
EV_STATE = const(2)  # a channel changed state
EV_FAULT = const(3)  # a fault flag was set or cleared
EV_REBOOT = const(4)  # the board booted (first event of every boot)
EV_WARNING = const(5)  # a warning (open load, under-voltage, ...)
EV_SHED = const(6)  # a channel was shed by a board-level rule
EV_RANGE = const(7)  # a channel's current left (flags low) or came back into the sensed range
EVENT_NAMES = ("", "trip", "state", "fault", "reboot", "warning", "shed", "range")

# --- reset causes (u8) ----------------------------------------------------------------
RESET_POWER_ON = const(0)
RESET_WATCHDOG = const(1)
RESET_SOFT = const(2)  # REBOOT command or software reset
RESET_BROWNOUT = const(3)
RESET_UNKNOWN = const(4)
RESET_NAMES = ("power_on", "watchdog", "soft", "brownout", "unknown")

# --- configuration status (u8), reported in HELLO and STATE ---------------------------
CFG_OK = const(0)  # loaded from the persisted file
CFG_MISSING = const(1)  # no file: factory configuration
CFG_CORRUPT = const(2)  # bad JSON or CRC: factory configuration
CFG_VERSION = const(3)  # unsupported config version: factory configuration
CFG_SAFE_MODE = const(4)  # watchdog reset loop: only protected channels on
CFG_FALLBACK = const(5)  # a copy was damaged: the last-known-good copy was loaded
CONFIG_STATUS_NAMES = ("ok", "missing", "corrupt", "version", "safe_mode", "fallback")

# --- capabilities (u16 bit mask in HELLO) ---------------------------------------------
CAP_AUTH = const(0x0001)  # actuation needs HMAC (always set by dxboard firmware)
CAP_SUBSCRIBE = const(0x0002)  # pushes measurement broadcasts
CAP_EVENTS = const(0x0004)  # pushes events
CAP_CONFIG = const(0x0008)  # get/set/save configuration
CAP_MODBUS = const(0x0010)  # serves Modbus TCP
CAP_CAN = const(0x0020)  # speaks CAN per dxboard.dbc
CAP_VOLTAGE = const(0x0040)  # measures input voltage
CAP_BATCH = const(0x0080)  # SUBSCRIBE's per_frame: several readings a MEASUREMENT_BATCH
CAPABILITY_NAMES = ("auth", "subscribe", "events", "config", "modbus", "can", "voltage",
                    "batch")

# --- error codes (u16) in ERROR replies -----------------------------------------------
# 1xx: the frame; 2xx: authentication; 3xx: the command; 4xx: the board.
E_BAD_CRC = const(100)
E_TOO_LARGE = const(101)
E_TRUNCATED = const(102)
E_VERSION = const(103)
E_UNKNOWN_TYPE = const(104)
E_MALFORMED = const(105)
E_NOT_A_REQUEST = const(106)
E_GARBAGE = const(107)
E_AUTH_REQUIRED = const(200)
E_BAD_TAG = const(201)
E_REPLAYED = const(202)
E_NO_SESSION = const(203)
E_BAD_CHANNEL = const(300)
E_LATCHED = const(301)
E_PROTECTED = const(302)
E_BAD_VALUE = const(303)
E_BUSY = const(304)
E_SWITCH_FAULT = const(305)
E_INHIBITED = const(306)
E_STORAGE = const(400)
E_INTERNAL = const(401)
ERROR_TEXT = {
    E_BAD_CRC: "bad CRC",
    E_TOO_LARGE: "frame too large",
    E_TRUNCATED: "truncated frame",
    E_VERSION: "unsupported protocol version",
    E_UNKNOWN_TYPE: "unknown message type",
    E_MALFORMED: "malformed payload",
    E_NOT_A_REQUEST: "message is not a request",
    E_GARBAGE: "bytes outside a frame skipped",
    E_AUTH_REQUIRED: "authentication required",
    E_BAD_TAG: "bad authentication tag",
    E_REPLAYED: "replayed or out-of-order counter",
    E_NO_SESSION: "no session: wait for HELLO",
    E_BAD_CHANNEL: "no such channel",
    E_LATCHED: "channel latched: clear it first",
    E_PROTECTED: "channel protected: needs the force flag",
    E_BAD_VALUE: "value out of range",
    E_BUSY: "busy",
    E_SWITCH_FAULT: "switch did not follow the command",
    E_INHIBITED: "inhibited by a board condition",
    E_STORAGE: "configuration storage failed",
    E_INTERNAL: "internal error",
}
