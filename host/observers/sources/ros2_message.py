"""A topic message from ROS 2: the CDR bytes as they came, decoded only when values are read.

``RosMessage`` is the observers' ``TopicMessage`` (time, topic, payload) with the message type's
name: a frequency observer counts it without deserialising anything (its ``stamp``, which the
frequency observer reads for every message, is read straight from the CDR bytes of the
``header`` that stamped types carry first: deserialising a 4 MB map to find it would starve the
daemon's loop); ``values`` (used by the
trend, matched-trend and diagnostic observers) deserialises once with
``rclpy.serialization.deserialize_message`` and converts with ``ros2_convert.to_dict``,
shared by every observer of the topic. Bytes that do not deserialise have no values (None),
like a payload that is not JSON on Zenoh.
"""

from __future__ import annotations

import functools
import logging
import struct
from dataclasses import dataclass
from functools import cached_property
from typing import Any

from rclpy.serialization import deserialize_message

from host.observers.payload import TopicMessage
from host.observers.sources.ros2_convert import message_type, to_dict

log = logging.getLogger(__name__)


CDR_LE = 0x01  # the second byte of the CDR encapsulation header: little-endian
STAMP_AT = 4  # the header's stamp (int32 sec, uint32 nanosec) right after the encapsulation


@functools.lru_cache(maxsize=256)
def _header_first(type_name: str) -> bool:
    """True when the type's first field is a ``std_msgs/Header`` (its stamp comes first)."""
    try:
        fields = message_type(type_name).get_fields_and_field_types()
    except Exception:  # an unknown type: no stamp to read
        return False
    return bool(fields) and next(iter(fields.items())) == ("header", "std_msgs/Header")


@dataclass(frozen=True)
class RosMessage(TopicMessage):
    type_name: str = ""

    @property
    def stamp(self) -> float | None:
        """The header's stamp in seconds, read from the bytes (None: no header first)."""
        if len(self.payload) < STAMP_AT + 8 or not _header_first(self.type_name):
            return None
        order = "<" if self.payload[1] == CDR_LE else ">"
        sec, nanosec = struct.unpack_from(order + "iI", self.payload, STAMP_AT)
        return float(sec) + float(nanosec) * 1e-9

    @cached_property
    def values(self) -> dict[str, Any] | None:
        try:
            return to_dict(deserialize_message(self.payload, message_type(self.type_name)))
        except Exception as exc:  # rclpy raises plain RuntimeErrors for bad CDR
            log.debug("%s: cannot deserialise %s: %s", self.topic, self.type_name, exc)
            return None
