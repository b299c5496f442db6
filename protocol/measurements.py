"""The board's pushed readings: MEASUREMENT (one a frame) and MEASUREMENT_BATCH (several).

A reading is every channel's current with the board's input voltage and switch and fault
masks, numbered per session (PROTOCOL.md §4.2). A board subscribed with ``per_frame`` 1 sends
each as a MEASUREMENT; with ``per_frame`` k > 1 (a board with capability ``batch``) it samples
at the same rate but sends up to k readings at a time in one MEASUREMENT_BATCH, whose layout
is a header and fixed-size records, so that a host reads a whole batch with one ``struct``
call (a hundred readings a second from each of several boards pass here)::

    MEASUREMENT_BATCH payload:
    +-------+----------+---------------------+-----+---------------------+
    | count | channels |      reading 1      | ... |    reading count    |
    |  u8   |    u8    | 14 + 4 x channels B |     |                     |
    +-------+----------+---------------------+-----+---------------------+
    reading: seq u32, uptime_ms u32, input_mv u16, on_mask u16, fault_mask u16,
             currents_ma: channels x i32   (a MEASUREMENT without its list count)

``count`` is 1..``MAX_PER_FRAME``; every reading has ``channels`` currents. Anything else (a
zero count, a count past the payload, a record cut short, bytes left over) is malformed
(``ValueError``, which the codec turns into E_MALFORMED), never a partial batch.
"""

import struct

from protocol.message import Message

MAX_PER_FRAME = 10  # readings a MEASUREMENT_BATCH may hold (SUBSCRIBE's per_frame 1..10)
_HEAD = 15  # MEASUREMENT: seq, uptime_ms, input_mv, on_mask, fault_mask, the count
_FORMATS: "dict[int, str]" = {}  # MEASUREMENT's format by channel count
_BATCH_FORMATS: "dict[tuple[int, int], str]" = {}  # MEASUREMENT_BATCH's by (count, channels)


class Measurement(Message):
    """Board -> host push: every channel's current, numbered so gaps show."""

    TYPE = 0x13
    DIR = "B"
    FIELDS = (
        ("seq", "I"),
        ("uptime_ms", "I"),
        ("input_mv", "H"),
        ("on_mask", "H"),
        ("fault_mask", "H"),
        ("currents_ma", "[i"),
    )

    def __init__(
        self,
        seq: int,
        uptime_ms: int,
        input_mv: int,
        on_mask: int,
        fault_mask: int,
        currents_ma: "list[int]",
        req_id: int = 0,
    ) -> None:
        self.seq = seq
        self.uptime_ms = uptime_ms
        self.input_mv = input_mv
        self.on_mask = on_mask
        self.fault_mask = fault_mask
        self.currents_ma = currents_ma
        self.req_id = req_id

    @classmethod
    def from_payload(cls, payload: bytes, req_id: int) -> "Message":
        """One ``struct`` unpack: the layout of ``FIELDS`` read whole, its format kept per
        channel count; what the generic reader would refuse is refused here too."""
        n = len(payload)
        if n < _HEAD:
            raise ValueError("payload too short")
        count = payload[_HEAD - 1]
        end = _HEAD + 4 * count
        if end > n:
            raise ValueError("list runs past the payload")
        if end != n:
            raise ValueError("%d unexpected bytes after the payload" % (n - end))
        fmt = _FORMATS.get(count)
        if fmt is None:
            fmt = ">IIHHHB%di" % count
            _FORMATS[count] = fmt
        v = struct.unpack_from(fmt, payload, 0)
        return cls(v[0], v[1], v[2], v[3], v[4], list(v[6:]), req_id)


def _batch_format(count: int, channels: int) -> str:
    fmt = _BATCH_FORMATS.get((count, channels))
    if fmt is None:
        fmt = ">BB" + ("IIHHH%di" % channels) * count
        _BATCH_FORMATS[(count, channels)] = fmt
    return fmt


class MeasurementBatch(Message):
    """Board -> host push: 1..``MAX_PER_FRAME`` readings of one session, oldest first, each a
    ``Measurement`` (``req_id`` 0) of the same channel count."""

    TYPE = 0x15
    DIR = "B"
    FIELDS = (("readings", Measurement),)  # the JSON form; the wire layout is the docstring's

    def __init__(self, readings: "list[Measurement]", req_id: int = 0) -> None:
        self.readings = readings
        self.req_id = req_id

    def payload(self) -> bytes:
        rs = self.readings
        count = len(rs)
        if not 1 <= count <= MAX_PER_FRAME:
            raise ValueError("a batch holds 1..%d readings, not %d" % (MAX_PER_FRAME, count))
        channels = len(rs[0].currents_ma)
        values = [count, channels]
        for r in rs:
            if len(r.currents_ma) != channels:
                raise ValueError("every reading of a batch has %d currents" % channels)
            values.extend((r.seq, r.uptime_ms, r.input_mv, r.on_mask, r.fault_mask))
            values.extend(r.currents_ma)
        try:
            return struct.pack(_batch_format(count, channels), *values)
        except (OverflowError, TypeError, getattr(struct, "error", ValueError)) as exc:
            raise ValueError("cannot pack MeasurementBatch: %s" % exc) from None

    @classmethod
    def from_payload(cls, payload: bytes, req_id: int) -> "Message":
        """The whole batch with one ``struct`` unpack; ``ValueError`` for a malformed one."""
        n = len(payload)
        if n < 2:
            raise ValueError("payload too short")
        count = payload[0]
        channels = payload[1]
        if not 1 <= count <= MAX_PER_FRAME:
            raise ValueError("a batch holds 1..%d readings, not %d" % (MAX_PER_FRAME, count))
        size = 14 + 4 * channels
        end = 2 + count * size
        if end > n:
            raise ValueError("%d readings of %d channels run past the payload"
                             % (count, channels))
        if end != n:
            raise ValueError("%d unexpected bytes after the payload" % (n - end))
        v = struct.unpack_from(_batch_format(count, channels), payload, 0)
        out = []
        step = 5 + channels
        for at in range(2, 2 + count * step, step):
            out.append(Measurement(v[at], v[at + 1], v[at + 2], v[at + 3], v[at + 4],
                                   list(v[at + 5:at + step])))
        return cls(out, req_id)
