"""MEASUREMENT's own decoder (one ``struct`` unpack) against the generic field reader, on
both interpreters: the same message from every good payload, a refusal (``ValueError``) for
every payload the generic reader refuses. MEASUREMENT_BATCH: its readings are exactly the
MEASUREMENTs they would have been, and a malformed batch (no readings, more than 10, a count
past the payload, a record cut short, bytes left over) is refused whole. SUBSCRIBE's optional
``per_frame`` byte: absent means 1, and per_frame 1 is sent as the one-byte SUBSCRIBE of old.
"""

import struct
import unittest

from protocol import messages as m
from protocol.fields import unpack
from protocol.measurements import MAX_PER_FRAME

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


def batch(count: int, channels: int, first: int = 40) -> "m.MeasurementBatch":
    return m.MeasurementBatch([
        m.Measurement(first + i, 1000 + 10 * i, 24000 - i, 0x3FF >> i, i, [
            (k - 3) * (i + 1) * 977 for k in range(channels)])
        for i in range(count)])


class TestMeasurementBatch(unittest.TestCase):
    def test_round_trip_and_layout(self) -> None:
        for count in (1, 2, 4, 10):
            for channels in (0, 1, 10, 16):
                b = batch(count, channels)
                data = b.payload()
                self.assertEqual(len(data), 2 + count * (14 + 4 * channels))
                self.assertEqual((data[0], data[1]), (count, channels))
                got = m.MeasurementBatch.from_payload(data, 0)
                self.assertEqual(got, b)
                # each record is a MEASUREMENT's payload without its list count
                for i, r in enumerate(got.readings):  # type: ignore[attr-defined]
                    one = r.payload()
                    at = 2 + i * (14 + 4 * channels)
                    self.assertEqual(data[at:at + 14 + 4 * channels], one[:14] + one[15:])
                    self.assertEqual(type(r.currents_ma), list)
                    self.assertEqual(r.req_id, 0)

    def test_the_largest_batch_fits_a_frame(self) -> None:
        from protocol.framing import MAX_PAYLOAD

        self.assertLessEqual(len(batch(MAX_PER_FRAME, 16).payload()), MAX_PAYLOAD)

    def test_malformed_batches_are_refused_whole(self) -> None:
        good = batch(2, 1).payload()  # 2 + 2 x 18 bytes
        bad = [
            good[:0], good[:1],  # no header
            b"\x00\x01",  # no readings
            b"\x0b\x00" + bytes(11 * 14),  # 11 readings of no channel: above the maximum
            b"\x03" + good[1:],  # the count runs past the payload
            good[:-1],  # the last record cut short
            good[:20],  # ... by most of it
            good + b"\x00",  # a byte left over
            b"\x02\x02" + good[2:],  # the channel count says more than there is
            b"\x02\x00" + good[2:],  # ... or less
        ]
        for data in bad:
            self.assertTrue(refused(lambda d: m.MeasurementBatch.from_payload(d, 0), data), data)

    def test_what_cannot_be_sent(self) -> None:
        mixed = m.MeasurementBatch([batch(1, 2).readings[0], batch(1, 3).readings[0]])
        for b in (m.MeasurementBatch([]), batch(11, 1), mixed):
            self.assertTrue(refused(lambda x: x.payload(), b))


class TestSubscribePerFrame(unittest.TestCase):
    def test_absent_means_one_and_one_is_the_old_frame(self) -> None:
        self.assertEqual(m.Subscribe(100).payload(), b"\x64")
        self.assertEqual(m.Subscribe(100, per_frame=1).payload(), b"\x64")
        self.assertEqual(m.Subscribe(100, per_frame=4).payload(), b"\x64\x04")
        old = m.Subscribe.from_payload(b"\x64", 7)
        self.assertEqual((old.rate_hz, old.per_frame, old.req_id), (100, 1, 7))  # type: ignore[attr-defined]
        new = m.Subscribe.from_payload(b"\x64\x0a", 7)
        self.assertEqual(new.per_frame, 10)  # type: ignore[attr-defined]
        self.assertEqual(m.Subscribe(100).to_dict(), {"rate_hz": 100})
        self.assertEqual(m.Subscribe(100, 4).to_dict(), {"rate_hz": 100, "per_frame": 4})

    def test_more_bytes_are_malformed(self) -> None:
        for data in (b"", b"\x64\x04\x00"):
            self.assertTrue(refused(lambda d: m.Subscribe.from_payload(d, 1), data), data)
        self.assertTrue(refused(lambda x: x.payload(), m.Subscribe(100, per_frame=256)))


if __name__ == "__main__":
    unittest.main()
