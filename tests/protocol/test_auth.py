"""HMAC-SHA256 written in the MicroPython subset, checked against RFC 4231's test cases."""

import unittest

from protocol.auth import equal, frame_tag, hmac_sha256


def unhex(s: str) -> bytes:
    return bytes(int(s[i : i + 2], 16) for i in range(0, len(s), 2))


# RFC 4231 test cases 1, 2, 3, 6 and 7 (HMAC-SHA-256)
CASES = (
    (
        b"\x0b" * 20,
        b"Hi There",
        "b0344c61d8db38535ca8afceaf0bf12b881dc200c9833da726e9376c2e32cff7",
    ),
    (
        b"Jefe",
        b"what do ya want for nothing?",
        "5bdcc146bf60754e6a042426089575c75a003f089d2739839dec58b964ec3843",
    ),
    (
        b"\xaa" * 20,
        b"\xdd" * 50,
        "773ea91e36800e46854db8ebd09181a72959098b3ef8c122d9635514ced565fe",
    ),
    (
        b"\xaa" * 131,
        b"Test Using Larger Than Block-Size Key - Hash Key First",
        "60e431591ee0b67f0d8a26aacbf5b77f8e0bc6213728c5140546040f0ee37f54",
    ),
    (
        b"\xaa" * 131,
        b"This is a test using a larger than block-size key and a larger than block-size data."
        b" The key needs to be hashed before being used by the HMAC algorithm.",
        "9b09ffa71b942fcb27635fbcd5b0e944bfdc63644f0713938a7f51535c3a35e2",
    ),
)


class TestHmac(unittest.TestCase):
    def test_rfc4231(self) -> None:
        for key, data, expected in CASES:
            with self.subTest(key=key[:4]):
                self.assertEqual(hmac_sha256(key, data), unhex(expected))

    def test_equal(self) -> None:
        self.assertTrue(equal(b"abc", b"abc"))
        self.assertFalse(equal(b"abc", b"abd"))
        self.assertFalse(equal(b"abc", b"ab"))
        self.assertTrue(equal(b"", b""))

    def test_frame_tag_is_16_bytes_and_depends_on_everything(self) -> None:
        tag = frame_tag(b"k", b"n" * 16, b"frame")
        self.assertEqual(len(tag), 16)
        self.assertNotEqual(tag, frame_tag(b"K", b"n" * 16, b"frame"))
        self.assertNotEqual(tag, frame_tag(b"k", b"N" * 16, b"frame"))
        self.assertNotEqual(tag, frame_tag(b"k", b"n" * 16, b"framE"))
