"""A topic message from ROS 2: the CDR bytes as they came, decoded only when values are read.

``RosMessage`` is the observers' ``Message`` (time, topic, payload) with the message type's
name: a frequency observer counts it without deserialising anything; ``values`` (used by the
trend, matched-trend and diagnostic observers) deserialises once with
``rclpy.serialization.deserialize_message`` and converts with ``host.ros.convert.to_dict``,
shared by every observer of the topic. Bytes that do not deserialise have no values (None),
like a payload that is not JSON on Zenoh.
"""

from __future__ import annotations

import logging
from dataclasses import dataclass
from functools import cached_property
from typing import Any

from rclpy.serialization import deserialize_message

from host.observers.payload import Message
from host.ros.convert import message_type, to_dict

log = logging.getLogger(__name__)


@dataclass(frozen=True)
class RosMessage(Message):
    type_name: str = ""

    @cached_property
    def values(self) -> dict[str, Any] | None:
        try:
            return to_dict(deserialize_message(self.payload, message_type(self.type_name)))
        except Exception as exc:  # rclpy raises plain RuntimeErrors for bad CDR
            log.debug("%s: cannot deserialise %s: %s", self.topic, self.type_name, exc)
            return None
