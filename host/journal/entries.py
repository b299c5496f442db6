"""The journal's rows: an ``Entry`` is one recorded event with its id and the daemon's times.

The events themselves (what the daemon saw, thought and did) are ``host.events``; the journal is
one reader of the daemon's event stream that keeps the journaled kinds (``JOURNALED``). Every
entry has a monotonic ``id`` (assigned by the writer, never reused), the ``wall`` time (seconds
since the epoch) and the daemon's ``mono`` time (its monotonic clock, for durations that a
wall-clock step must not distort), both given by the daemon, and the event as its ``payload``.
"""

from __future__ import annotations

from dataclasses import dataclass

from host.events import JSON, Kind, Payload


@dataclass(frozen=True)
class Entry:
    """One journal row: id, times given by the daemon, and the typed payload."""

    id: int
    wall: float
    mono: float
    payload: Payload

    @property
    def kind(self) -> Kind:
        return self.payload.kind

    def to_json(self) -> JSON:
        return {"id": self.id, "kind": self.kind.value, "wall": self.wall, "mono": self.mono,
                "data": self.payload.to_json()}
