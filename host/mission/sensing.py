"""ψ from layer 1 to layer 3: the world's state, as the skills report it, in the KB's atoms.

The skill servers report the world's state with every result and on request (``place``: the
room or door the robot is in, ``doors``: each door open or not, ``locked``: the locked doors,
``marked``: the victims with a marker) and some skills report what they found (``detect``:
``victims`` seen, in ``place``; ``level``: the laser is level). ``Sensing`` turns these into
literals of the mission's domain, by the predicate names of the ``sensing:`` section of
``mission.yaml``::

    sensing: {place: at, doors: open, locked: locked, found: victim-in, seen: seen,
              marked: marked, level: level, victim_type: victim, room_type: room,
              door_type: door}

``(at R)`` is true for the room the robot is in and false for every other room (in a doorway,
where a navigation halted half-way leaves it, the nearer of the door's rooms: the world's
``room``); ``(open D)`` as each door is; ``(locked D)`` for each locked door and its negation
for the others (when the world reports locks and ``locked`` names the predicate); a victim seen
becomes an object (type ``victim_type``) with ``(found V R)`` and ``(seen V)``; ``(marked V)``
for every marker, and its negation for every other victim known. These are observations: where
they contradict the KB, they override it (paper 001 §III-C).
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

from host.planning.temporal_pddl import Literal

KEYS = ("place", "doors", "locked", "found", "seen", "marked", "level", "victim_type", "room_type",
        "door_type")


@dataclass(frozen=True)
class Sensing:
    place: str = "at"
    doors: str = "open"
    locked: str = ""  # "" : locks are not sensed
    found: str = "victim-in"
    seen: str = "seen"
    marked: str = "marked"
    level: str = "level"
    victim_type: str = "victim"
    room_type: str = "room"
    door_type: str = "door"

    def observe(self, objects: Mapping[str, str], state: Mapping[str, Any],
                data: Mapping[str, Any] | None = None
                ) -> tuple[list[Literal], dict[str, str]]:
        """The literals observed, and the new objects (name -> type) they mention."""
        data = data or {}
        lits: list[Literal] = []
        new: dict[str, str] = {}
        rooms = [o for o, t in objects.items() if t == self.room_type]
        place = state.get("place")
        room = state.get("room", place)  # in a doorway: the nearer room
        if isinstance(room, str):
            lits += [((self.place, r), r == room) for r in rooms]
        doors = state.get("doors")
        if isinstance(doors, dict):
            lits += [((self.doors, d), bool(v)) for d, v in doors.items()
                     if objects.get(d) == self.door_type]
        locked = state.get("locked")
        if self.locked and isinstance(locked, list):
            lits += [((self.locked, d), d in locked) for d, t in objects.items()
                     if t == self.door_type]
        victims = data.get("victims")
        where = data.get("place", place)
        if isinstance(victims, list) and isinstance(where, str) and where in rooms:
            for v in victims:
                if isinstance(v, str):
                    if v not in objects:
                        new[v] = self.victim_type
                    lits += [((self.found, v, where), True), ((self.seen, v), True)]
        marked = state.get("marked")
        if isinstance(marked, list):  # every marker the world shows, and no other
            known = [v for v, t in [*objects.items(), *new.items()] if t == self.victim_type]
            lits += [((self.marked, v), v in marked) for v in known]
        if data.get("level") is True:
            lits.append(((self.level,), True))
        return lits, new
