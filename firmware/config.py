"""The board's persisted configuration: versioned JSON with a CRC, written atomically.

A configuration is a dict ``{"version": 1, "board": {...}, "channels": [{...}, ...]}`` whose
fields, defaults and ranges are the tables of ``protocol.settings`` (the same as the
protocol's CONFIG messages; ``defaults``, ``check_channel`` and ``check_board`` are its). The
file adds ``"crc"``: the CRC-32
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

from protocol import settings
from protocol.compat import crc32
from protocol.constants import CFG_CORRUPT, CFG_MISSING, CFG_OK, CFG_VERSION

VERSION = 1
FILE = "config.json"
TMP = "config.tmp"

defaults = settings.defaults
default_channel = settings.default_channel
default_board = settings.default_board
check_channel = settings.check_channel
check_board = settings.check_board


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
    cfg = settings.merge(obj, n, VERSION)[0]
    if cfg is None or not isinstance(obj.get("board"), dict) \
            or not isinstance(obj.get("channels"), list):
        return None, CFG_CORRUPT
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
