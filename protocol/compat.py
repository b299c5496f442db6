"""What differs between MicroPython and CPython, in one place.

``const`` is MicroPython's compile-time constant marker (identity on CPython);
``crc32`` is ``binascii.crc32`` where the port has it, else a table-driven fallback;
``IS_MICROPYTHON`` tells the two apart for the rare place that must know.
"""

import sys

IS_MICROPYTHON = sys.implementation.name == "micropython"


def const(value: int) -> int:
    """Identity on CPython; MicroPython's compiler folds ``X = const(...)`` itself."""
    return value


if IS_MICROPYTHON:  # the real one, which the compiler knows
    from micropython import const  # type: ignore[no-redef, import-untyped, unused-ignore] # noqa


try:
    from binascii import crc32 as _crc32

    def crc32(data: bytes) -> int:
        """CRC-32 (IEEE 802.3, the zlib/Ethernet polynomial) of ``data``."""
        return _crc32(data) & 0xFFFFFFFF

except ImportError:  # a port built without it
    _TABLE = []
    for _n in range(256):
        _c = _n
        for _ in range(8):
            _c = (_c >> 1) ^ 0xEDB88320 if _c & 1 else _c >> 1
        _TABLE.append(_c)

    def crc32(data: bytes) -> int:
        """CRC-32 (IEEE 802.3, the zlib/Ethernet polynomial) of ``data``."""
        c = 0xFFFFFFFF
        for b in data:
            c = _TABLE[(c ^ b) & 0xFF] ^ (c >> 8)
        return c ^ 0xFFFFFFFF
