"""MEASUREMENT's own decoder (one ``struct`` unpack) against the generic field reader, on
both interpreters: the same message from every good payload, a refusal (``ValueError``) for
every payload the generic reader refuses.
"""

import struct
import unittest

from protocol import messages as m
from protocol.fields import unpack

CURRENTS = (
    [],
    [0],
    [1510, -3, 0, 702, 0, 0, 0, 4980, 0, 0],
    [-0x80000000, 0x7FFFFFFF, -1, 1],
    list(range(-40, 40)),
    [7] * 255,
)


def payload(seq: int, currents: "list[int]") -> bytes:
    return m.Measurement(seq, 0xFFFFFFFF - seq, 24090, 0x0089, 0xFFFF, currents).payload()


def generic(data: bytes) -> "m.Message":
    """What ``Message.from_payload`` reads: the generic path, field by field."""
    values, end = unpack(data, m.Measurement.FIELDS)
    if end != len(data):
        raise ValueError("trailing bytes")
    msg = m.Measurement(**values)
    msg.req_id = 9
    return msg


def refused(read: "object", data: bytes) -> bool:
    try:
        read(data)  # type: ignore[operator]
    except ValueError:
        return True
    return False


class TestMeasurementDecoder(unittest.TestCase):
    def test_same_message_as_the_generic_reader(self) -> None:
        for seq, currents in enumerate(CURRENTS):
            data = payload(seq + 1, currents)
            fast = m.Measurement.from_payload(data, 9)
            self.assertEqual(fast, generic(data))
            self.assertEqual(fast.currents_ma, currents)
            self.assertEqual(type(fast.currents_ma), list)
            self.assertEqual(fast.req_id, 9)

    def test_refuses_what_the_generic_reader_refuses(self) -> None:
        good = payload(17, [1, -2, 3])
        bad = [good[:n] for n in range(len(good))]  # every truncation
        bad.append(good + b"\x00")  # a byte too many
        bad.append(good + b"\x00" * 4)  # an item too many
        bad.append(good[:14] + b"\x05" + good[15:])  # the count says more than there is
        bad.append(good[:14] + b"\x02" + good[15:])  # ... or less
        for data in bad:
            self.assertTrue(refused(generic, data), data)
            self.assertTrue(refused(lambda d: m.Measurement.from_payload(d, 1), data), data)

    def test_layout_is_the_documented_one(self) -> None:
        data = struct.pack(">IIHHHB2i", 5, 61260, 24090, 3, 1, 2, -7, 70000)
        msg = m.Measurement.from_payload(data, 0)
        self.assertEqual((msg.seq, msg.uptime_ms, msg.input_mv, msg.on_mask, msg.fault_mask,
                          msg.currents_ma), (5, 61260, 24090, 3, 1, [-7, 70000]))


if __name__ == "__main__":
    unittest.main()
