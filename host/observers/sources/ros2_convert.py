"""ROS 2 messages as plain dicts, and message types by name.

``to_dict(msg)`` walks any generated message through ``get_fields_and_field_types()``:
nested messages become dicts, sequences and arrays become lists, ``bytes``/``byte`` fields
their integers, so an observer names a value by path (``twist.twist.angular.z`` of
``nav_msgs/msg/Odometry``) exactly as in the message definition. A
``diagnostic_msgs/DiagnosticArray`` gets one more key per status, its name, holding
``level`` (an int), ``message``, ``hardware_id`` and the key/values (a value that reads as a
number becomes a float): ``"hokuyo_node: hokuyo.level"`` or ``"hokuyo_node: hokuyo.rate_hz"``
is a path a threshold can name, as ROS's diagnostic analyzers address statuses by name.

``message_type("sensor_msgs/msg/LaserScan")`` imports the class (a ``TypeError`` naming the
type when its package is not installed).
"""

from __future__ import annotations

import array
import importlib
from functools import cache
from typing import Any

DIAGNOSTIC_ARRAY = "diagnostic_msgs/msg/DiagnosticArray"


@cache
def message_type(name: str) -> Any:
    """The message class of ``pkg/msg/Type``."""
    parts = name.split("/")
    if len(parts) != 3 or parts[1] != "msg" or not all(parts):
        raise TypeError(f"{name!r} is not a message type like sensor_msgs/msg/LaserScan")
    try:
        return getattr(importlib.import_module(f"{parts[0]}.msg"), parts[2])
    except (ImportError, AttributeError):
        raise TypeError(f"message type {name} is not installed "
                        f"(pip install ros-{parts[0].replace('_', '-')})") from None


def type_name(msg_type: Any) -> str:
    """``pkg/msg/Type`` of a message class."""
    pkg = msg_type.__module__.split(".")[0]
    return f"{pkg}/msg/{msg_type.__name__}"


def _value(v: Any) -> Any:
    if hasattr(v, "get_fields_and_field_types"):
        return to_dict(v)
    if isinstance(v, bytes):
        return v[0] if len(v) == 1 else list(v)
    if isinstance(v, list | tuple | array.array) or type(v).__name__ == "ndarray":
        return [_value(x) for x in v]
    if hasattr(v, "item"):  # a numpy scalar
        return v.item()
    return v


def to_dict(msg: Any) -> dict[str, Any]:
    """Every field of ``msg``, recursively, as plain Python values."""
    out = {name: _value(getattr(msg, name)) for name in msg.get_fields_and_field_types()}
    if type_name(type(msg)) == DIAGNOSTIC_ARRAY:
        for status in out["status"]:
            named: dict[str, Any] = {k: status[k] for k in ("level", "message", "hardware_id")}
            for kv in status["values"]:
                named[kv["key"]] = _number(kv["value"])
            out.setdefault(status["name"], named)
    return out


def _number(text: str) -> Any:
    try:
        return float(text)
    except ValueError:
        return text
