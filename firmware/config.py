"""The board's persisted configuration: versioned JSON with a CRC, written atomically.

A configuration is a dict ``{"version": 1, "board": {...}, "channels": [{...}, ...]}`` whose
field names are exactly those of the protocol's CONFIG message (tables ``BOARD_FIELDS`` and
``CHANNEL_FIELDS`` below, each with its default and range). The file adds ``"crc"``: the CRC-32
(hex) of the canonical serialisation of everything else (keys sorted, no spaces), so the file
itself may be formatted freely and reads the same on MicroPython, whose dicts keep no order.

``load(storage, n)`` returns ``(config, status)``: status ``CFG_OK``, or ``CFG_MISSING`` /
``CFG_CORRUPT`` / ``CFG_VERSION`` with safe defaults (every channel off at power-up, nothing
protected, the limits of the defaults below). ``save`` writes ``config.tmp`` then renames it
over ``config.json``, so a power loss leaves either the old or the new file, never half of one.
``check_channel`` / ``check_board`` validate a partial update completely before anything is
applied: a bad value changes nothing.
"""

import json

from protocol.compat import crc32
from protocol.constants import CFG_CORRUPT, CFG_MISSING, CFG_OK, CFG_VERSION

VERSION = 1
FILE = "config.json"
TMP = "config.tmp"

# name -> (default, minimum, maximum); for strings and lists the range bounds the length
# (lists: the bounds apply to each item, at most MAX_LIST items; lo < 0 marks strings)
CHANNEL_FIELDS = {
    "name": ("", 0, 16),
    "rated_ma": (1000, 1, 60000),
    "inrush_ms": (100, 0, 10000),
    "inrush_factor_x10": (40, 10, 250),
    "trip_factor_x10": (30, 10, 250),
    "trip_samples": (2, 1, 100),
    "overload_start_x100": (110, 100, 1000),
    "i2t_ms": (3100, 1, 600000),
    "retry_ms": ([1000, 2000, 5000], 0, 3600000),
    "short_retries": (1, 0, 10),
    "retry_reset_ms": (60000, 0, 3600000),
    "open_load_ma": (0, 0, 60000),
    "open_load_ms": (1000, 0, 600000),
    "stuck_on_ma": (50, 1, 60000),
    "stuck_on_ms": (200, 0, 600000),
    "powerup": (False, 0, 1),
    "priority": (128, 0, 255),
    "protected": (False, 0, 1),
}
BOARD_FIELDS = {
    "board_id": ("dxboard", 0, 32),
    "total_limit_ma": (20000, 0, 1000000),
    "uv_warn_mv": (0, 0, 100000),
    "uv_shed_mv": (0, 0, 100000),
    "uv_off_mv": (0, 0, 100000),
    "uv_hyst_mv": (500, 0, 100000),
    "tick_ms": (10, 1, 1000),
    "powerup_spacing_ms": (200, 0, 60000),
    "deadman_ms": (0, 0, 86400000),
    "deadman_on_mask": (0, 0, 0xFFFF),
    "modbus_write": (False, 0, 1),
    "modbus_allow": ([], -1, 64),  # lo < 0: a list of strings
    "key": ("", 0, 128),
}
MAX_LIST = 8


def default_channel(ch: int) -> dict:  # type: ignore[type-arg]
    c = {}
    for k, spec in CHANNEL_FIELDS.items():
        d = spec[0]
        c[k] = list(d) if isinstance(d, list) else d
    c["name"] = "ch%d" % ch
    return c


def default_board() -> dict:  # type: ignore[type-arg]
    b = {}
    for k, spec in BOARD_FIELDS.items():
        d = spec[0]
        b[k] = list(d) if isinstance(d, list) else d
    return b


def defaults(n: int) -> dict:  # type: ignore[type-arg]
    return {"version": VERSION, "board": default_board(),
            "channels": [default_channel(i) for i in range(n)]}


def _check_value(spec: tuple, v: object) -> bool:  # type: ignore[type-arg]
    d, lo, hi = spec
    if isinstance(d, bool):
        return isinstance(v, bool)
    if isinstance(d, int):
        return isinstance(v, int) and not isinstance(v, bool) and lo <= v <= hi
    if isinstance(d, str):
        return isinstance(v, str) and lo <= len(v) <= hi
    if isinstance(d, list):
        if not isinstance(v, list) or len(v) > MAX_LIST:
            return False
        for item in v:
            if lo < 0:  # a list of strings, each at most ``hi`` characters
                if not isinstance(item, str) or len(item) > hi:
                    return False
            elif not isinstance(item, int) or isinstance(item, bool) or not lo <= item <= hi:
                return False
        return True
    return False


def _check(table: dict, fields: object) -> "str | None":  # type: ignore[type-arg]
    """None if every field of ``fields`` is known and in range, else the offending name."""
    if not isinstance(fields, dict):
        return "?"
    for k, v in fields.items():
        spec = table.get(k)
        if spec is None or not _check_value(spec, v):
            return str(k)
    return None


def check_channel(fields: object) -> "str | None":
    return _check(CHANNEL_FIELDS, fields)


def check_board(fields: object) -> "str | None":
    bad = _check(BOARD_FIELDS, fields)
    if bad is None and isinstance(fields, dict) and "key" in fields:
        try:
            bytes.fromhex(fields["key"])
        except ValueError:
            return "key"
    return bad


def canonical(obj: object) -> str:
    """JSON with sorted keys and no spaces: the same text on every interpreter."""
    if isinstance(obj, dict):
        return "{" + ",".join(
            json.dumps(k) + ":" + canonical(obj[k]) for k in sorted(obj)) + "}"
    if isinstance(obj, (list, tuple)):
        return "[" + ",".join(canonical(x) for x in obj) + "]"
    return json.dumps(obj)


def dumps(cfg: dict) -> bytes:  # type: ignore[type-arg]
    """The file text of ``cfg``: one line per channel, with its CRC."""
    body = {"version": cfg["version"], "board": cfg["board"], "channels": cfg["channels"]}
    crc = "%08x" % crc32(canonical(body).encode())
    lines = ['{"version":%d,"crc":"%s",' % (cfg["version"], crc),
             '"board":' + canonical(cfg["board"]) + ",", '"channels":[']
    chans = cfg["channels"]
    for i, c in enumerate(chans):
        lines.append(canonical(c) + ("," if i < len(chans) - 1 else ""))
    lines.append("]}")
    return ("\n".join(lines) + "\n").encode()


def parse(data: bytes, n: int) -> tuple:  # type: ignore[type-arg]
    """``(config, status)`` from file bytes: a full config with defaults filled in, or None."""
    try:
        obj = json.loads(data)
    except (ValueError, UnicodeError):
        return None, CFG_CORRUPT
    if not isinstance(obj, dict):
        return None, CFG_CORRUPT
    if obj.get("version") != VERSION:
        return None, CFG_VERSION if isinstance(obj.get("version"), int) else CFG_CORRUPT
    crc = obj.pop("crc", None)
    if not isinstance(crc, str) or crc != "%08x" % crc32(canonical(obj).encode()):
        return None, CFG_CORRUPT
    board = obj.get("board")
    chans = obj.get("channels")
    if check_board(board) is not None or not isinstance(chans, list) or len(chans) > n:
        return None, CFG_CORRUPT
    cfg = defaults(n)
    cfg["board"].update(board)
    for i, c in enumerate(chans):
        if check_channel(c) is not None:
            return None, CFG_CORRUPT
        cfg["channels"][i].update(c)
    return cfg, CFG_OK


def load(storage: object, n: int) -> tuple:  # type: ignore[type-arg]
    """``(config, status)``: the persisted configuration, or safe defaults and the reason."""
    try:
        data = storage.read(FILE)  # type: ignore[attr-defined]
    except OSError:
        data = None
    if data is None:
        return defaults(n), CFG_MISSING
    cfg, status = parse(data, n)
    if cfg is None:
        return defaults(n), status
    return cfg, status


def save(storage: object, cfg: dict) -> None:  # type: ignore[type-arg]
    """Write ``cfg`` atomically: temporary file, then rename. Raises OSError on failure."""
    storage.write(TMP, dumps(cfg))  # type: ignore[attr-defined]
    storage.rename(TMP, FILE)  # type: ignore[attr-defined]
