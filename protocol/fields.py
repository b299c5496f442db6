"""Field kinds of message payloads and the generic packer/unpacker that reads them.

A message class lists its payload as ``FIELDS``: ``(name, kind)`` pairs in wire order. Kinds:

    "B" "H" "I"      unsigned 8/16/32-bit integers, big-endian
    "b" "h" "i"      signed 8/16/32-bit integers, big-endian
    "?"              a flag byte: 0 or 1 (anything else is malformed)
    "str"            u8 length, then that many bytes of UTF-8 (at most 255 bytes)
    "nonce"          exactly 16 raw bytes
    "[H" "[I" "[i"   u8 count, then count integers of that kind
    a Record class   u8 count, then count records, each laid out by the record's FIELDS

Unpacking checks every length and value and raises ``ValueError`` on anything malformed, so
the framing layer can turn it into a ``BadFrame`` event; trailing bytes are malformed too.
"""

import struct

from protocol.compat import IS_MICROPYTHON

if False:  # typing only; MicroPython never imports typing
    from typing import Any

    Fields = tuple[tuple[str, Any], ...]

_INT_KINDS = "BHIbhi?"
_SIZES = {"B": 1, "H": 2, "I": 4, "b": 1, "h": 2, "i": 4, "?": 1}
_STRUCT_ERROR = getattr(struct, "error", ValueError)  # MicroPython raises ValueError
# MicroPython's struct does not range-check, so there pack() checks with these bounds;
# CPython's struct raises on its own, and only flags ("?" packed as "B") need a check.
_CHECK_ALL = IS_MICROPYTHON
_RANGES = {
    "B": (0, 0xFF),
    "H": (0, 0xFFFF),
    "I": (0, 0xFFFFFFFF),
    "b": (-0x80, 0x7F),
    "h": (-0x8000, 0x7FFF),
    "i": (-0x80000000, 0x7FFFFFFF),
    "?": (0, 1),
}


def _int(value: object, kind: str, name: str) -> int:
    v: int = int(value)  # type: ignore[call-overload]
    lo, hi = _RANGES[kind]
    if v < lo or v > hi:
        raise ValueError("field %s = %d does not fit %s" % (name, v, kind))
    return v


class Record:
    """A fixed group of fields inside a list (a channel's status, say); subclasses define
    ``FIELDS`` and an ``__init__`` taking those fields as keyword arguments."""

    FIELDS: "Fields" = ()

    def __eq__(self, other: object) -> bool:
        return type(other) is type(self) and to_dict(self) == to_dict(other)

    def __repr__(self) -> str:
        return "%s(%s)" % (
            type(self).__name__,
            ", ".join("%s=%r" % (n, getattr(self, n)) for n, _ in self.FIELDS),
        )


def _prefix(fields: "Fields") -> "tuple[str, list[str], int, list[int]]":
    """The longest run of leading integer fields: one struct format, the names, the size,
    and the positions of the flags among them."""
    fmt = ">"
    names: "list[str]" = []
    flags: "list[int]" = []
    for name, kind in fields:
        if not (isinstance(kind, str) and kind in _INT_KINDS):
            break
        if kind == "?":
            flags.append(len(names))
        fmt += "B" if kind == "?" else kind
        names.append(name)
    return fmt, names, struct.calcsize(fmt), flags


_PREFIX_CACHE: "dict[int, tuple[str, list[str], int, list[int]]]" = {}


def _prefix_of(fields: "Fields") -> "tuple[str, list[str], int, list[int]]":
    key = id(fields)
    got = _PREFIX_CACHE.get(key)
    if got is None:
        got = _prefix(fields)
        _PREFIX_CACHE[key] = got
    return got


def pack(obj: object, fields: "Fields") -> bytes:
    """The payload bytes of ``obj`` laid out by ``fields``; bad values raise ValueError."""
    fmt, names, _, flags = _prefix_of(fields)
    out = []
    try:
        if names:
            if _CHECK_ALL:
                kinds = fmt[1:]
                ints = [_int(getattr(obj, n), kinds[i], n) for i, n in enumerate(names)]
            else:
                ints = [getattr(obj, n) for n in names]
                for i in flags:
                    _int(ints[i], "?", names[i])
            out.append(struct.pack(fmt, *ints))
        for name, kind in fields[len(names) :]:
            value = getattr(obj, name)
            if isinstance(kind, str):
                if kind in _INT_KINDS:
                    v = _int(value, kind, name)
                    out.append(struct.pack(">" + ("B" if kind == "?" else kind), v))
                elif kind == "str":
                    raw = value.encode()
                    if len(raw) > 255:
                        raise ValueError("string field %s longer than 255 bytes" % name)
                    out.append(bytes((len(raw),)) + raw)
                elif kind == "nonce":
                    if len(value) != 16:
                        raise ValueError("field %s must be 16 bytes" % name)
                    out.append(bytes(value))
                else:  # "[H", "[I", "[i"
                    if len(value) > 255:
                        raise ValueError("list field %s longer than 255 items" % name)
                    if _CHECK_ALL:
                        value = [_int(v, kind[1], name) for v in value]
                    out.append(struct.pack(">B%d%s" % (len(value), kind[1]), len(value), *value))
            else:
                if len(value) > 255:
                    raise ValueError("list field %s longer than 255 items" % name)
                out.append(bytes((len(value),)))
                for rec in value:
                    out.append(pack(rec, kind.FIELDS))
    except (_STRUCT_ERROR, OverflowError, TypeError, AttributeError) as exc:
        raise ValueError("cannot pack %s: %s" % (type(obj).__name__, exc)) from None
    return b"".join(out)


def unpack(payload: bytes, fields: "Fields", pos: int = 0) -> "tuple[dict[str, Any], int]":
    """Read ``fields`` from ``payload`` at ``pos``; return (dict of values, next position)."""
    fmt, names, size, _ = _prefix_of(fields)
    values: "dict[str, Any]" = {}
    n = len(payload)
    if names:
        if pos + size > n:
            raise ValueError("payload too short")
        ints = struct.unpack_from(fmt, payload, pos)
        pos += size
        for i in range(len(names)):
            values[names[i]] = ints[i]
    for name, kind in fields:
        if name in values:
            continue
        if isinstance(kind, str):
            if kind in _INT_KINDS:
                size = _SIZES[kind]
                if pos + size > n:
                    raise ValueError("payload too short")
                fmt = ">" + ("B" if kind == "?" else kind)
                values[name] = struct.unpack_from(fmt, payload, pos)[0]
                pos += size
            elif kind == "str":
                if pos >= n or pos + 1 + payload[pos] > n:
                    raise ValueError("string runs past the payload")
                length = payload[pos]
                try:
                    values[name] = bytes(payload[pos + 1 : pos + 1 + length]).decode()
                except UnicodeError:
                    raise ValueError("string field %s is not UTF-8" % name) from None
                pos += 1 + length
            elif kind == "nonce":
                if pos + 16 > n:
                    raise ValueError("payload too short")
                values[name] = bytes(payload[pos : pos + 16])
                pos += 16
            else:
                if pos >= n:
                    raise ValueError("payload too short")
                count = payload[pos]
                item = kind[1]
                end = pos + 1 + count * _SIZES[item]
                if end > n:
                    raise ValueError("list runs past the payload")
                values[name] = list(struct.unpack_from(">%d%s" % (count, item), payload, pos + 1))
                pos = end
        else:
            if pos >= n:
                raise ValueError("payload too short")
            count = payload[pos]
            pos += 1
            items = []
            for _ in range(count):
                vals, pos = unpack(payload, kind.FIELDS, pos)
                items.append(kind(**vals))
            values[name] = items
    for name, kind in fields:
        if kind == "?":
            if values[name] > 1:
                raise ValueError("flag %s must be 0 or 1" % name)
            values[name] = bool(values[name])
    return values, pos


def to_dict(obj: object) -> "dict[str, Any]":
    """A JSON-friendly dict of ``obj``'s fields (nonces as hex, records as dicts)."""
    out: "dict[str, Any]" = {}
    for name, kind in obj.FIELDS:  # type: ignore[attr-defined]
        value = getattr(obj, name)
        if kind == "nonce":
            value = "".join("%02x" % b for b in value)
        elif not isinstance(kind, str):
            value = [to_dict(r) for r in value]
        elif kind[0] == "[":
            value = list(value)
        out[name] = value
    return out


def from_dict_values(data: "dict[str, Any]", fields: "Fields") -> "dict[str, Any]":
    """The constructor arguments for ``fields`` from a dict made by ``to_dict``."""
    values: "dict[str, Any]" = {}
    for name, kind in fields:
        value = data[name]
        if kind == "nonce":
            value = bytes(int(value[i : i + 2], 16) for i in range(0, len(value), 2))
        elif not isinstance(kind, str):
            value = [kind(**from_dict_values(r, kind.FIELDS)) for r in value]
        values[name] = value
    return values
