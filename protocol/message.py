"""The base of every message of PROTOCOL.md §4: payload from ``FIELDS``, equality, JSON form.

A message class has ``TYPE`` (the frame's type byte), ``FIELDS`` (its payload layout, see
``protocol.fields``), ``AUTH`` (True when the board requires an HMAC trailer, PROTOCOL.md
§5), ``DIR`` (who sends it: "H" host to board, "B" board to host) and a ``req_id`` (the
frame's request id: a reply carries its request's id; pushes carry 0).

``OPTIONAL`` lists trailing single-byte fields that a later revision added to a request
(PROTOCOL.md §11): ``(name, default)`` pairs, in wire order. They are sent only when one of
them differs from its default (so a message that uses none is byte for byte what it always
was), read when present, and shown by ``to_dict`` only when they differ from the default (so
the golden vectors of the old form stay as they are). The catalogue itself is in
``protocol/messages.py``; the measurement pushes in ``protocol/measurements.py``.
"""

from protocol.fields import from_dict_values, pack, to_dict, unpack

if False:  # typing only; MicroPython never imports typing
    from typing import Any


class Message:
    TYPE = 0
    FIELDS: "tuple[tuple[str, Any], ...]" = ()
    OPTIONAL: "tuple[tuple[str, int], ...]" = ()
    AUTH = False
    DIR = "H"

    req_id = 0

    def payload(self) -> bytes:
        body = pack(self, self.FIELDS)
        if not self.OPTIONAL:
            return body
        extra = [getattr(self, n) for n, _ in self.OPTIONAL]
        used = 0  # how many optional bytes must go out: up to the last non-default one
        for i in range(len(extra)):
            if extra[i] != self.OPTIONAL[i][1]:
                used = i + 1
        for i in range(used):
            if not 0 <= extra[i] <= 0xFF:
                raise ValueError("field %s = %r does not fit B" % (self.OPTIONAL[i][0],
                                                                   extra[i]))
        return body + bytes(extra[:used])

    @classmethod
    def from_payload(cls, payload: bytes, req_id: int) -> "Message":
        values, end = unpack(payload, cls.FIELDS)
        left = len(payload) - end
        if left > len(cls.OPTIONAL):
            raise ValueError("%d unexpected bytes after the payload"
                             % (left - len(cls.OPTIONAL)))
        for i in range(left):
            values[cls.OPTIONAL[i][0]] = payload[end + i]
        msg = cls(**values)
        msg.req_id = req_id
        return msg

    def to_dict(self) -> "dict[str, Any]":
        out = to_dict(self)
        for name, default in self.OPTIONAL:
            value = getattr(self, name)
            if value != default:
                out[name] = value
        return out

    def __eq__(self, other: object) -> bool:
        return (
            type(other) is type(self)
            and self.req_id == getattr(other, "req_id", None)
            and self.to_dict() == other.to_dict()
        )

    def __repr__(self) -> str:
        args = ["%s=%r" % (n, getattr(self, n)) for n, _ in self.FIELDS + self.OPTIONAL]
        args.append("req_id=%d" % self.req_id)
        return "%s(%s)" % (type(self).__name__, ", ".join(args))

    @classmethod
    def from_dict(cls, data: "dict[str, Any]", req_id: int = 0) -> "Message":
        """The message of a dict made by ``to_dict`` (optional fields may be absent)."""
        values = from_dict_values(data, cls.FIELDS)
        for name, _ in cls.OPTIONAL:
            if name in data:
                values[name] = data[name]
        msg = cls(**values)
        msg.req_id = req_id
        return msg
