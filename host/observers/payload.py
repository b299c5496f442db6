"""The payload convention for topic values, and the topic ``TopicMessage`` every source delivers.

A topic payload is one JSON object in UTF-8 (``{"twist": {"angular": {"z": 0.1}}}``), so an
observer picks a value by key: ``pick(obj, "twist.angular.z")`` follows dots through nested
objects (and integer indexes through lists). Anything else (not UTF-8, not JSON, not an object)
is still a message — it counts for a topic's frequency — but carries no values: ``value()``
returns None. Drivers publish with ``encode`` (``host.observers.publisher``) and observers read
with ``Message.value()``; a ROS bridge would convert messages to this form.

The publisher's own time of a message (its *stamp*, ``Message.stamp``) is read, in this order,
from ``stamp`` (seconds), ``t_ms`` (milliseconds: the virtual robot's device frames) or a ROS
``header.stamp`` (``{"sec", "nanosec"}``). A frequency observer judges a topic's rate on these
stamps where a message has one, so messages bunched on their way (a stalled consumer, a busy
machine) still show the rate they were sent at.
"""

from __future__ import annotations

import json
from collections.abc import Mapping
from dataclasses import dataclass, field
from functools import cached_property
from typing import Any


def encode(values: Mapping[str, Any]) -> bytes:
    """The wire form of ``values`` (compact JSON, UTF-8)."""
    return json.dumps(values, separators=(",", ":"), allow_nan=False).encode()


def decode(payload: bytes) -> dict[str, Any] | None:
    """The JSON object in ``payload``, or None when it is not one."""
    try:
        obj = json.loads(payload)
    except (UnicodeDecodeError, ValueError):
        return None
    return obj if isinstance(obj, dict) else None


def _index_ok(part: str, size: int) -> bool:
    return part.lstrip("-").isdigit() and -size <= int(part) < size


def pick(obj: Mapping[str, Any] | None, key: str) -> Any:
    """The value at dotted ``key`` in ``obj`` (None when absent)."""
    cur: Any = obj
    for part in key.split("."):
        if isinstance(cur, Mapping):
            cur = cur.get(part)
        elif isinstance(cur, list) and _index_ok(part, len(cur)):
            cur = cur[int(part)]
        else:
            return None
        if cur is None:
            return None
    return cur


def pick_number(obj: Mapping[str, Any] | None, key: str) -> float | None:
    """The number at ``key`` (booleans and non-finite values are not numbers here)."""
    v = pick(obj, key)
    if isinstance(v, bool) or not isinstance(v, int | float):
        return None
    f = float(v)
    return f if f == f and abs(f) != float("inf") else None


def stamp_of(obj: Mapping[str, Any] | None) -> float | None:
    """The publisher's stamp in ``obj`` in seconds (None when it carries none)."""
    s = pick_number(obj, "stamp")
    if s is not None:
        return s
    ms = pick_number(obj, "t_ms")
    if ms is not None:
        return ms / 1000.0
    sec = pick_number(obj, "header.stamp.sec")
    if sec is None:
        return None
    return sec + (pick_number(obj, "header.stamp.nanosec") or 0.0) * 1e-9


@dataclass(frozen=True)
class TopicMessage:
    """One message of ``topic`` received at ``time`` (host monotonic seconds)."""

    time: float
    topic: str
    payload: bytes = field(default=b"", repr=False)

    @cached_property
    def values(self) -> dict[str, Any] | None:
        """The decoded JSON object (decoded once, shared by every observer of the topic)."""
        return decode(self.payload)

    def number(self, key: str) -> float | None:
        return pick_number(self.values, key)

    @property
    def stamp(self) -> float | None:
        """The publisher's time of this message, seconds on its own clock (``stamp_of``)."""
        return stamp_of(self.values)
