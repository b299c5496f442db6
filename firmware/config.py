"""The board's persisted configuration: two copies with a sequence number, each with a CRC.

A configuration is a dict ``{"version": 1, "board": {...}, "channels": [{...}, ...]}`` whose
fields, defaults and ranges are the tables of ``protocol.settings`` (the same as the protocol's
CONFIG messages; ``defaults``, ``check_channel`` and ``check_board`` are its). A file adds
``"seq"`` (how many saves came before, counting up) and ``"crc"``: the CRC-32 (hex) of the
canonical serialisation of everything else (keys sorted, no spaces), so the file itself may be
formatted freely and reads the same on MicroPython, whose dicts keep no order.

Two slots, ``SLOTS``, hold the last two saves. ``save`` writes the slot that does *not* hold the
newest good copy (the older one, or a damaged or missing one), with the next ``seq``, and reads
it back; the newest good copy is never touched. No rename: a power cut at any point of a save
(also the remove-then-rename a FAT file system makes of a rename) leaves the previous copy
intact, and a half-written slot fails its CRC. Once a slot is written and read back, an earlier
firmware's single ``config.json`` is removed (it is superseded). ``load(storage, n)`` takes the
good copy with the highest ``seq`` (a file ``config.json`` of an older firmware counts as
``seq`` 0) and returns ``(config, status)``: ``CFG_OK``; ``CFG_FALLBACK`` when a copy was
damaged and the last-known-good one was loaded; or, with no good copy at all, ``None`` and
``CFG_MISSING`` / ``CFG_CORRUPT`` / ``CFG_VERSION``, for the board to boot its factory
configuration (``Board``: the one built into the firmware when it was flashed, else the
defaults).
"""

import json

from protocol import settings
from protocol.compat import crc32
from protocol.constants import CFG_CORRUPT, CFG_FALLBACK, CFG_MISSING, CFG_OK, CFG_VERSION

if False:  # typing only; MicroPython never imports typing (the block is compiled away)
    from typing import Any

    from firmware.hal import Storage

    Config = dict[str, Any]  # a configuration (``protocol.settings``): JSON-shaped

VERSION = 1
SLOTS = ("config.a.json", "config.b.json")
LEGACY = "config.json"  # the single file of earlier firmware: read, never written

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


def dumps(cfg: "Config", seq: int = 0) -> bytes:
    """The file text of ``cfg`` as save number ``seq``: one line per channel, with its CRC."""
    body = {"version": cfg["version"], "seq": seq, "board": cfg["board"],
            "channels": cfg["channels"]}
    crc = "%08x" % crc32(canonical(body).encode())
    lines = ['{"version":%d,"seq":%d,"crc":"%s",' % (cfg["version"], seq, crc),
             '"board":' + canonical(cfg["board"]) + ",", '"channels":[']
    chans = cfg["channels"]
    for i, c in enumerate(chans):
        lines.append(canonical(c) + ("," if i < len(chans) - 1 else ""))
    lines.append("]}")
    return ("\n".join(lines) + "\n").encode()


def parse_seq(data: bytes, n: int) -> "tuple[Config | None, int, int]":
    """``(config, status, seq)`` from file bytes: a full config with defaults filled in, or
    None with the reason (``seq`` -1 then)."""
    try:
        obj = json.loads(data)
    except (ValueError, UnicodeError):
        return None, CFG_CORRUPT, -1
    if not isinstance(obj, dict):
        return None, CFG_CORRUPT, -1
    if obj.get("version") != VERSION:
        return None, CFG_VERSION if isinstance(obj.get("version"), int) else CFG_CORRUPT, -1
    crc = obj.pop("crc", None)
    if not isinstance(crc, str) or crc != "%08x" % crc32(canonical(obj).encode()):
        return None, CFG_CORRUPT, -1
    seq = obj.get("seq", 0)
    if not isinstance(seq, int) or isinstance(seq, bool) or seq < 0:
        return None, CFG_CORRUPT, -1
    if not isinstance(obj.get("board"), dict) or not isinstance(obj.get("channels"), list):
        return None, CFG_CORRUPT, -1
    cfg = settings.merge(obj, n, VERSION)[0]
    if cfg is None:
        return None, CFG_CORRUPT, -1
    return cfg, CFG_OK, seq


def parse(data: bytes, n: int) -> "tuple[Config | None, int]":
    """``(config, status)`` from the bytes of one file (see ``parse_seq``)."""
    cfg, status, _ = parse_seq(data, n)
    return cfg, status


def _read(storage: "Storage", name: str) -> "bytes | None":
    try:
        return storage.read(name)
    except OSError:
        return None


def _copies(storage: "Storage", n: int) -> "list[tuple[str, Config | None, int, int]]":
    """``(name, config or None, status, seq)`` of every copy that exists."""
    out = []
    for name in SLOTS + (LEGACY,):
        data = _read(storage, name)
        if data is not None:
            cfg, status, seq = parse_seq(data, n)
            out.append((name, cfg, status, seq))
    return out


def exists(storage: "Storage") -> bool:
    """Whether the storage holds any copy of a configuration (good or not)."""
    return any(_read(storage, name) is not None for name in SLOTS + (LEGACY,))


def load(storage: "Storage", n: int) -> "tuple[Config | None, int]":
    """``(config, status)``: the newest good copy, or ``(None, why)`` when there is none."""
    best = None
    damaged = 0
    for _name, cfg, status, seq in _copies(storage, n):
        if cfg is None:
            damaged = status if not damaged or status == CFG_VERSION else damaged
        elif best is None or seq > best[1]:
            best = (cfg, seq)
    if best is not None:
        return best[0], CFG_FALLBACK if damaged else CFG_OK
    return None, damaged or CFG_MISSING


def save(storage: "Storage", cfg: "Config") -> None:
    """Write ``cfg`` to the slot without the newest good copy, then read it back. Raises
    OSError when the storage fails or the copy does not read back the same."""
    n = len(cfg["channels"])
    seqs = {}
    top = -1
    for name, good, _status, seq in _copies(storage, n):
        if good is not None:
            seqs[name] = seq
            top = seq if seq > top else top
    target = SLOTS[0]
    if seqs.get(SLOTS[0], -1) > seqs.get(SLOTS[1], -1):
        target = SLOTS[1]
    data = dumps(cfg, top + 1)
    storage.write(target, data)
    if _read(storage, target) != data:
        raise OSError("the configuration did not read back as written")
    if LEGACY in seqs or _read(storage, LEGACY) is not None:
        storage.remove(LEGACY)
