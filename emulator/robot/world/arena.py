"""The arena: a pyrobosim world (rooms, doors, rubble, victims, the robot) and what the skills
ask of it.

``load_arena(system_dir)`` reads ``SYSTEM_DIR/arena/world.yaml`` with pyrobosim's own loader (its
YAML schema; ``$PWD`` is the arena directory) and checks what the skills rely on: one robot with
a path planner and a field-of-view sensor (the thermal camera), rooms, and hallways (the doors).
A mistake is a ``RobotModelError`` naming the file and the fix. pyrobosim is imported only here,
and only when a world is served (``dxboard emulate --robot --world``): its GUI (dash/plotly in
pyrobosim 5) is never started, its sensor threads never run (the world steps them), and its
loggers are turned down to warnings.

``Arena`` is the world seen through what the skill servers need: where the robot is (its room or
door), the doors and whether they are open, a path to a room (pyrobosim's world-graph planner,
deterministic), the victims in the camera's view, opening and closing a door, and leaving a
marker beside a victim. It never reads the clock and never moves by itself: the skills
(``emulator.robot.world.skills``) move the robot along a path as the board's truth allows.
"""

from __future__ import annotations

import itertools
import logging
import math
import pathlib
from dataclasses import dataclass
from typing import Any

from emulator.robot.config import RobotModelError

log = logging.getLogger(__name__)

ARENA_DIR = "arena"
WORLD_FILE = "world.yaml"
VICTIM = "victim"
MARKER = "marker"


@dataclass(frozen=True)
class Motion:
    """A planned path as poses with times: (t_s, x, y, yaw) at constant speed."""

    points: tuple[tuple[float, float, float, float], ...]

    @property
    def duration_s(self) -> float:
        return self.points[-1][0] if self.points else 0.0

    def at(self, t_s: float) -> tuple[float, float, float]:
        """The pose ``t_s`` seconds along (clamped to the ends), interpolated linearly."""
        pts = self.points
        if t_s <= pts[0][0]:
            return pts[0][1:]
        for (t0, x0, y0, a0), (t1, x1, y1, a1) in itertools.pairwise(pts):
            if t_s <= t1:
                k = 0.0 if t1 <= t0 else (t_s - t0) / (t1 - t0)
                turn = math.remainder(a1 - a0, math.tau)
                return x0 + k * (x1 - x0), y0 + k * (y1 - y0), a0 + k * turn
        return pts[-1][1:]


def _quiet(names: list[str]) -> None:
    for name in ["pyrobosim", *names]:
        logging.getLogger(name).setLevel(logging.WARNING)


class Arena:
    """The pyrobosim world and its one robot."""

    def __init__(self, world: Any, source: str) -> None:
        from pyrobosim.sensors.fov import FOVSensor

        self.world = world
        self.source = source
        if len(world.robots) != 1:
            raise RobotModelError(f"{source}: the arena needs exactly one robot, not "
                                  f"{len(world.robots)}; fix 'robots'")
        self.robot = world.robots[0]
        if self.robot.path_planner is None:
            raise RobotModelError(f"{source}: robot {self.robot.name!r} has no path_planner; "
                                  "add one (type: world_graph)")
        cams = [s for s in self.robot.sensors.values() if isinstance(s, FOVSensor)]
        if not cams:
            raise RobotModelError(f"{source}: robot {self.robot.name!r} has no field-of-view "
                                  "sensor (the thermal camera); add one under sensors (type: fov)")
        self.camera = cams[0]
        if not world.rooms:
            raise RobotModelError(f"{source}: the arena has no rooms; add some under 'rooms'")
        executor = self.robot.path_executor
        self.speed = float(getattr(executor, "linear_velocity", 1.0) or 1.0)
        self.turn_rate = getattr(executor, "max_angular_velocity", None)
        self.marked: list[str] = []
        self.jammed = False  # the marker dispenser: the next mark leaves nothing
        _quiet([world.name, *(r.name for r in world.robots)])

    # --- where things are -------------------------------------------------------------------

    def rooms(self) -> list[str]:
        return [r.name for r in self.world.rooms]

    def doors(self) -> dict[str, bool]:
        """Every door (hallway) and whether it is open."""
        return {h.name: bool(h.is_open) for h in self.world.hallways}

    def door_rooms(self, door: str) -> tuple[str, str]:
        h = self._door(door)
        return h.room_start.name, h.room_end.name

    def victims(self) -> list[str]:
        return sorted(o.name for o in self.world.objects if o.category == VICTIM)

    def pose(self) -> tuple[float, float, float]:
        p = self.robot.get_pose()
        return float(p.x), float(p.y), float(p.get_yaw())

    def set_pose(self, x: float, y: float, yaw: float) -> None:
        from pyrobosim.utils.pose import Pose

        self.robot.set_pose(Pose(x=x, y=y, yaw=yaw))

    def place(self) -> str | None:
        """The room or door the robot is in (None: between them, which the world forbids)."""
        loc = self.robot.location
        while loc is not None and loc.__class__.__name__ not in ("Room", "Hallway"):
            loc = getattr(loc, "parent", None)
        return None if loc is None else str(loc.name)

    def room(self) -> str | None:
        """The room the robot is in; in a doorway, the nearer of the door's two rooms (a
        navigation stopped half-way through a door leaves the robot there)."""
        place = self.place()
        if place is None or place in self.rooms():
            return place
        x, y, _ = self.pose()
        rooms = [self.world.get_room_by_name(r) for r in self.door_rooms(place)]
        near = min(rooms, key=lambda r: (r.centroid[0] - x) ** 2 + (r.centroid[1] - y) ** 2)
        return str(near.name)

    def room_of(self, name: str) -> str | None:
        """The room an object (a victim) lies in."""
        obj = self.world.get_object_by_name(name)
        loc = None if obj is None else obj.parent
        while loc is not None and loc.__class__.__name__ != "Room":
            loc = getattr(loc, "parent", None)
        return None if loc is None else str(loc.name)

    def in_view(self, category: str = VICTIM) -> list[str]:
        """The objects of ``category`` inside the camera's field of view now."""
        self.camera.update()
        return sorted(o.name for o in self.camera.get_measurement() if o.category == category)

    # --- what the skills change -------------------------------------------------------------

    def plan(self, room: str) -> Motion | None:
        """A path from the robot's pose to ``room``, timed at the robot's speed (None: there is
        no way, e.g. behind a closed door). Slow (tens of ms): run it off the event loop."""
        from pyrobosim.utils.trajectory import get_constant_speed_trajectory

        if self.world.get_room_by_name(room) is None:
            raise ValueError(f"no room {room!r} (rooms: {', '.join(self.rooms())})")
        if self.place() == room:
            x, y, a = self.pose()
            return Motion(((0.0, x, y, a),))
        path = self.robot.plan_path(goal=room)
        if path is None or path.num_poses < 2:
            return None
        traj = get_constant_speed_trajectory(path, linear_velocity=self.speed,
                                             max_angular_velocity=self.turn_rate)
        if traj is None:
            return None
        return Motion(tuple((float(t), float(p.x), float(p.y), float(p.get_yaw()))
                            for t, p in zip(traj.t_pts, traj.poses, strict=True)))

    def set_door(self, door: str, open_: bool) -> str:
        """Open or close a door; returns what went wrong ('' when done). The planner's graph is
        rebuilt, so that paths follow the doors."""
        h = self._door(door)
        if bool(h.is_open) == open_:
            return ""
        if open_:
            res = self.world.open_location(h)
        else:
            res = self.world.close_location(h, ignore_robots=[])
        if not res.is_success():
            return str(res.message or res.status.name)
        self.robot.path_planner.reset()
        return ""

    def locked(self) -> list[str]:
        return sorted(d for d in self.doors() if self._door(d).is_locked)

    def set_lock(self, door: str, locked: bool) -> str:
        """Lock or unlock a door (a locked door does not open); '' when done."""
        h = self._door(door)
        if bool(h.is_locked) == locked:
            return ""
        res = self.world.lock_location(h) if locked else self.world.unlock_location(h)
        return "" if res.is_success() else str(res.message or res.status.name)

    def mark(self, victim: str) -> None:
        """Leave a marker beside ``victim`` (on its rubble pile)."""
        obj = self.world.get_object_by_name(victim)
        if obj is None:
            raise ValueError(f"no victim {victim!r}")
        name = f"{MARKER}_{victim}"
        if self.world.get_object_by_name(name) is None:
            self.world.add_object(name=name, category=MARKER, parent=obj.parent, show=False)
        if victim not in self.marked:
            self.marked.append(victim)

    def chance(self, skill: str) -> bool:
        """pyrobosim's simulated outcome of one execution of ``skill`` (its execution options:
        the success probability, seeded); True when no options are given. Its ``delay`` is not
        slept here: the skills spend their time on the emulator's clock."""
        opts = self.robot.action_execution_options.get(skill)
        if opts is None:
            return True
        return float(opts.rng.random()) <= float(opts.success_probability)

    def state(self) -> dict[str, Any]:
        x, y, a = self.pose()
        return {"pose": [round(x, 3), round(y, 3), round(a, 3)], "place": self.place(),
                "room": self.room(),
                "doors": self.doors(), "locked": self.locked(), "marked": list(self.marked)}

    def _door(self, door: str) -> Any:
        h = self.world.get_hallway_by_name(door)
        if h is None:
            raise ValueError(f"no door {door!r} (doors: {', '.join(self.doors())})")
        return h


def load_arena(system_dir: str | pathlib.Path) -> Arena:
    """The arena of ``SYSTEM_DIR/arena/world.yaml``; ``RobotModelError`` names what is wrong."""
    path = pathlib.Path(system_dir) / ARENA_DIR / WORLD_FILE
    if not path.is_file():
        raise RobotModelError(f"{path}: no arena here (a pyrobosim world file)",)
    try:
        from pyrobosim.core import WorldYamlLoader
    except ImportError as exc:  # pragma: no cover - a dependency of dxboard
        raise RobotModelError(f"{path}: pyrobosim is not installed ({exc})") from None
    _quiet([])
    try:
        world = WorldYamlLoader().from_file(path)
    except (OSError, ValueError, KeyError, TypeError, RuntimeError, AttributeError) as exc:
        raise RobotModelError(f"{path}: pyrobosim cannot load it: {exc}; fix the file") from None
    return Arena(world, str(path))
