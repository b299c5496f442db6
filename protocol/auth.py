"""HMAC-SHA256 in the MicroPython subset, and the actuation tag of PROTOCOL.md §5.

MicroPython has ``hashlib.sha256`` but no ``hmac`` module, so HMAC (RFC 2104) is written out
here and tested against CPython's ``hmac``. ``frame_tag`` computes the 16-byte tag that
authenticates an actuation frame: the first 16 bytes of HMAC-SHA256(key, session nonce ||
frame bytes from the start marker through the counter). ``equal`` compares in constant time.
"""

import hashlib

TAG_LEN = 16
COUNTER_LEN = 4
TRAILER_LEN = COUNTER_LEN + TAG_LEN
NONCE_LEN = 16
_BLOCK = 64


def hmac_sha256(key: bytes, data: bytes) -> bytes:
    """HMAC-SHA256 of ``data`` under ``key`` (RFC 2104)."""
    if len(key) > _BLOCK:
        key = hashlib.sha256(key).digest()
    key = key + bytes(_BLOCK - len(key))
    inner = hashlib.sha256(bytes(b ^ 0x36 for b in key))
    inner.update(data)
    outer = hashlib.sha256(bytes(b ^ 0x5C for b in key))
    outer.update(inner.digest())
    return outer.digest()


def equal(a: bytes, b: bytes) -> bool:
    """Compare two byte strings in time that depends only on their lengths."""
    if len(a) != len(b):
        return False
    diff = 0
    for i in range(len(a)):
        diff |= a[i] ^ b[i]
    return diff == 0


def frame_tag(key: bytes, nonce: bytes, signed: bytes) -> bytes:
    """The 16-byte tag over the session ``nonce`` and the ``signed`` frame bytes."""
    return hmac_sha256(key, nonce + signed)[:TAG_LEN]
