"""The configuration fields, written once: wire layout, default, range; and the one merge.

A board's configuration is ``{"version": 1, "board": {...}, "channels": [{...}, ...]}``. Every
field is one row below: its name, its kind on the wire (``protocol.fields`` kinds, in the order
of CHANNEL_CONFIG / BOARD_CONFIG, PROTOCOL.md §4.4; ``None`` for the board fields that
never travel: the HMAC ``key``, hex; ``listen``, the IPv4 address the board's servers
listen on, "" for its own address on the network, never every interface unless it says
"0.0.0.0"; ``tug_port``, the TCP port of the original TEDUSAR board's format, which has no
authentication, 0 (off) unless flashed, the original board's being 5000; and ``tug_switch``,
whether its clients may switch channels, never a protected one off), its default and its range.
The message classes (``protocol.messages``), the firmware's persisted file
(``firmware/config.py``), the Modbus register map (``protocol/modbus_map.py``), the emulator's
board config and ``dxboard flash`` all read these tables; a range never exceeds what the wire
kind can carry, so every value a board accepts can be reported.

Ranges: integers ``lo..hi``; strings a length ``lo..hi``; lists at most ``MAX_LIST`` items,
each in ``lo..hi``; ``modbus_allow`` is a list of dotted IPv4 addresses (``u32`` on the wire).
``check_channel`` / ``check_board`` validate a partial update completely (None, or the first
offending name) so that a bad value changes nothing; ``merge(partial, n)`` is the single way a
partial configuration (a robot's ``board.json``, a flashed file) becomes a whole one.
"""

MAX_LIST = 8

# name, wire kind, default, lo, hi -- in CHANNEL_CONFIG order (after its "channel" byte)
CHANNEL = (
    ("name", "str", "", 0, 16),
    ("rated_ma", "I", 1000, 1, 60000),
    ("inrush_ms", "H", 100, 0, 10000),
    ("inrush_factor_x10", "B", 40, 10, 250),
    ("trip_factor_x10", "B", 30, 10, 250),
    ("trip_samples", "B", 2, 1, 100),
    ("overload_start_x100", "B", 110, 100, 255),
    ("i2t_ms", "H", 3100, 1, 65535),
    ("retry_reset_ms", "I", 60000, 0, 3600000),
    ("short_retries", "B", 1, 0, 10),
    ("open_load_ma", "H", 0, 0, 60000),
    ("open_load_ms", "H", 1000, 0, 65535),
    ("stuck_on_ma", "H", 50, 1, 60000),
    ("stuck_on_ms", "H", 200, 0, 65535),
    ("powerup", "?", False, 0, 1),
    ("priority", "B", 128, 0, 255),
    ("protected", "?", False, 0, 1),
    ("retry_ms", "[H", [1000, 2000, 5000], 0, 65535),
)

# name, wire kind (None: never on the wire), default, lo, hi -- in BOARD_CONFIG order
BOARD: "tuple[tuple[str, str | None, object, int, int], ...]" = (
    ("total_limit_ma", "I", 20000, 0, 1000000),
    ("uv_warn_mv", "H", 0, 0, 65535),
    ("uv_shed_mv", "H", 0, 0, 65535),
    ("uv_off_mv", "H", 0, 0, 65535),
    ("uv_hyst_mv", "H", 500, 0, 65535),
    ("tick_ms", "H", 10, 1, 1000),
    ("powerup_spacing_ms", "H", 200, 0, 60000),
    ("deadman_ms", "I", 0, 0, 86400000),
    ("deadman_on_mask", "H", 0, 0, 0xFFFF),
    ("modbus_write", "?", False, 0, 1),
    ("board_id", "str", "dxboard", 0, 32),
    ("modbus_allow", "[I", [], 0, 0),
    ("key", None, "", 0, 128),
    ("listen", None, "", 0, 64),
    ("tug_port", None, 0, 0, 65535),
    ("tug_switch", None, False, 0, 1),
)

CHANNEL_WIRE = (("channel", "B"),) + tuple((r[0], r[1]) for r in CHANNEL)
BOARD_WIRE = tuple((r[0], r[1]) for r in BOARD if r[1] is not None)
CHANNEL_KEYS = tuple(r[0] for r in CHANNEL)
BOARD_KEYS = tuple(r[0] for r in BOARD)
BOARD_WIRE_KEYS = tuple(name for name, _ in BOARD_WIRE)
_CHANNEL_SPEC = {r[0]: r for r in CHANNEL}
_BOARD_SPEC = {r[0]: r for r in BOARD}


# --- IPv4 addresses (modbus_allow) ----------------------------------------------------


def ip_to_int(text: str) -> int:
    """``"10.0.0.1"`` -> 0x0A000001; ValueError if it is not a dotted IPv4 address."""
    parts = text.split(".") if isinstance(text, str) else []
    if len(parts) != 4:
        raise ValueError("not an IPv4 address: %r" % (text,))
    n = 0
    for p in parts:
        if not p.isdigit() or len(p) > 3 or int(p) > 255:
            raise ValueError("not an IPv4 address: %r" % (text,))
        n = n * 256 + int(p)
    return n


def int_to_ip(n: int) -> str:
    return "%d.%d.%d.%d" % ((n >> 24) & 255, (n >> 16) & 255, (n >> 8) & 255, n & 255)


# --- defaults ---------------------------------------------------------------------------


def _copy(value: object) -> object:
    return list(value) if isinstance(value, list) else value


def default_channel(ch: int) -> dict:  # type: ignore[type-arg]
    c = {}
    for row in CHANNEL:
        c[row[0]] = _copy(row[2])
    c["name"] = "ch%d" % ch
    return c


def default_board() -> dict:  # type: ignore[type-arg]
    b = {}
    for row in BOARD:
        b[row[0]] = _copy(row[2])
    return b


def defaults(n: int, version: int = 1) -> dict:  # type: ignore[type-arg]
    return {"version": version, "board": default_board(),
            "channels": [default_channel(i) for i in range(n)]}


# --- checks -------------------------------------------------------------------------------


def _int_ok(v: object, lo: int, hi: int) -> bool:
    return isinstance(v, int) and not isinstance(v, bool) and lo <= v <= hi


def check_value(row: tuple, v: object) -> bool:  # type: ignore[type-arg]
    """Whether ``v`` is a valid value for the field ``row`` (a row of CHANNEL or BOARD)."""
    name, kind, d, lo, hi = row
    if isinstance(d, bool):
        return isinstance(v, bool)
    if isinstance(d, int):
        return _int_ok(v, lo, hi)
    if isinstance(d, str):
        if not isinstance(v, str) or not lo <= len(v) <= hi:
            return False
        try:
            if name == "key":
                bytes.fromhex(v)
            elif name == "listen" and v:
                ip_to_int(v)
        except ValueError:
            return False
        return True
    if not isinstance(v, list) or len(v) > MAX_LIST:
        return False
    for item in v:
        if kind == "[I":  # modbus_allow: dotted IPv4 addresses
            try:
                ip_to_int(item)
            except ValueError:
                return False
        elif not _int_ok(item, lo, hi):
            return False
    return True


def _check(spec: dict, fields: object) -> "str | None":  # type: ignore[type-arg]
    if not isinstance(fields, dict):
        return "?"
    for k, v in fields.items():
        row = spec.get(k)
        if row is None or not check_value(row, v):
            return str(k)
    return None


def check_channel(fields: object) -> "str | None":
    """None if every field of ``fields`` is a known channel field in range, else its name."""
    return _check(_CHANNEL_SPEC, fields)


def check_board(fields: object) -> "str | None":
    """None if every field of ``fields`` is a known board field in range, else its name."""
    return _check(_BOARD_SPEC, fields)


def merge(partial: object, n: int, version: int = 1) -> tuple:  # type: ignore[type-arg]
    """``(config, None)``: the defaults for ``n`` channels with ``partial``'s ``board`` and
    ``channels`` sections applied, or ``(None, where)`` naming the first bad field (e.g.
    ``"board: uv_warn_mv"``, ``"channel 3: rated_ma"``, ``"channels"``)."""
    cfg = defaults(n, version)
    if not isinstance(partial, dict):
        return None, "the configuration is not an object"
    board = partial.get("board", {})
    bad = check_board(board)
    if bad is not None:
        return None, "board: " + bad
    cfg["board"].update(board)
    chans = partial.get("channels", [])
    if not isinstance(chans, list) or len(chans) > n:
        return None, "channels (a list of at most %d)" % n
    for i in range(len(chans)):
        bad = check_channel(chans[i])
        if bad is not None:
            return None, "channel %d: %s" % (i, bad)
        cfg["channels"][i].update(chans[i])
    return cfg, None
