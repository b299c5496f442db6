"""The robot's skill servers in the world: navigate, detect victims, mark a victim, open a door,
level the laser — each a goal stepped on the emulator's clock.

A goal needs some of the truth's resources (``emulator.robot.world.truth``) and an amount of
*working* time; a step advances it only while none of them is blocked, so a skill stalls, and
resumes by itself, exactly as the board, the devices and the drivers allow::

    skill     args            needs          works for                  then
    navigate  {"to": ROOM}    base, lidar    the path's time at speed   at ROOM (the pose
                                             (planned when accepted)    moves along the way)
    detect    {}              camera         2 s (a sweep of the head)  the victims in view
    mark      {"victim": V}   camera, base   1.5 s                      a marker beside V (V must
                                                                        be in view, same room)
    open      {"door": D}     base           2.5 s                      D open (the robot is in
                                                                        one of D's rooms)
    level     {}              mount          1 s                        the laser is level

``check`` refuses a goal at once (an unknown room, a door not beside the robot); a navigation
that finds no path fails at once; pyrobosim's execution options decide a simulated failure
when the goal starts (``Arena.chance``). ``step(now_ms)`` returns a ``Progress``: how far, what
it waits for (the blocked resources' symptoms), and when done, the result and its data.
"""

from __future__ import annotations

from collections.abc import Awaitable, Callable
from dataclasses import dataclass, field
from typing import Any, ClassVar

from emulator.robot.world.arena import Arena, Motion
from emulator.robot.world.truth import Truth

RunBlocking = Callable[[Callable[[], Any]], Awaitable[Any]]


@dataclass
class Progress:
    progress: float
    waiting: tuple[str, ...] = ()
    done: bool = False
    success: bool = False
    message: str = ""
    data: dict[str, Any] = field(default_factory=dict)


class Goal:
    """One skill execution; subclasses say what it needs and what it does when done."""

    skill: ClassVar[str] = ""
    needs: ClassVar[tuple[str, ...]] = ()
    work_ms: int = 0

    def __init__(self, arena: Arena, truth: Truth, args: dict[str, Any]) -> None:
        self.arena = arena
        self.truth = truth
        self.args = args
        self.worked_ms = 0
        self.last_ms: int | None = None
        self.failed = ""

    def check(self) -> str:
        """Why the goal cannot be taken at all ('' when it can)."""
        return ""

    async def prepare(self, run_blocking: RunBlocking) -> None:
        """Slow work before the first step (planning), off the event loop."""
        if not self.arena.chance(self.skill):
            self.failed = f"simulated {self.skill} failure (pyrobosim execution options)"

    def waiting(self) -> tuple[str, ...]:
        return tuple(w for w in (self.truth.blocked(n) for n in self.needs) if w is not None)

    def step(self, now_ms: int) -> Progress:
        if self.failed:
            return Progress(self.fraction(), done=True, message=self.failed)
        dt = 0 if self.last_ms is None else max(0, now_ms - self.last_ms)
        self.last_ms = now_ms
        waiting = self.waiting()
        if not waiting:
            self.worked_ms = min(self.work_ms, self.worked_ms + dt)
            self.advance()
        if self.worked_ms >= self.work_ms and not waiting:
            return self.finish()
        return Progress(self.fraction(), waiting)

    def fraction(self) -> float:
        return 1.0 if self.work_ms <= 0 else round(self.worked_ms / self.work_ms, 3)

    def advance(self) -> None:
        """The world changes while working (the robot moves)."""

    def finish(self) -> Progress:
        return Progress(1.0, done=True, success=True)

    def _arg(self, key: str) -> str:
        value = self.args.get(key)
        if not isinstance(value, str) or not value:
            raise ValueError(f"{self.skill} needs {key!r} (a name)")
        return value


class Navigate(Goal):
    skill = "navigate"
    needs = ("base", "lidar")

    def __init__(self, arena: Arena, truth: Truth, args: dict[str, Any]) -> None:
        super().__init__(arena, truth, args)
        self.to = self._arg("to")
        self.motion: Motion | None = None

    def check(self) -> str:
        if self.to not in self.arena.rooms():
            return f"no room {self.to!r} (rooms: {', '.join(self.arena.rooms())})"
        return ""

    async def prepare(self, run_blocking: RunBlocking) -> None:
        await super().prepare(run_blocking)
        self.motion = await run_blocking(lambda: self.arena.plan(self.to))
        if self.motion is None:
            closed = [d for d, o in self.arena.doors().items() if not o]
            self.failed = (f"no path from {self.arena.place()} to {self.to}"
                           + (f" (closed: {', '.join(closed)})" if closed else ""))
        else:
            self.work_ms = round(self.motion.duration_s * 1000)

    def advance(self) -> None:
        if self.motion is not None:
            self.arena.set_pose(*self.motion.at(self.worked_ms / 1000.0))

    def finish(self) -> Progress:
        place = self.arena.place()
        if place != self.to:
            return Progress(1.0, done=True, message=f"ended in {place}, not {self.to}",
                            data={"place": place})
        return Progress(1.0, done=True, success=True, data={"place": place})


class Detect(Goal):
    skill = "detect"
    needs = ("camera",)
    work_ms = 2000

    def finish(self) -> Progress:
        place = self.arena.place()  # walls stop the camera: only this room's victims
        seen = [v for v in self.arena.in_view() if self.arena.room_of(v) == place]
        return Progress(1.0, done=True, success=True,
                        data={"victims": seen, "place": place})


class Mark(Goal):
    skill = "mark"
    needs = ("camera", "base")
    work_ms = 1500

    def __init__(self, arena: Arena, truth: Truth, args: dict[str, Any]) -> None:
        super().__init__(arena, truth, args)
        self.victim = self._arg("victim")

    def check(self) -> str:
        if self.victim not in self.arena.victims():
            return f"no victim {self.victim!r} in the arena"
        return ""

    def finish(self) -> Progress:
        if self.arena.room_of(self.victim) != self.arena.place() \
                or self.victim not in self.arena.in_view():
            return Progress(1.0, done=True, message=f"{self.victim} is not in view")
        if self.arena.jammed:  # the dispenser jammed: it reports a marker it did not leave
            self.arena.jammed = False
        else:
            self.arena.mark(self.victim)
        return Progress(1.0, done=True, success=True, data={"marked": self.victim})


class Open(Goal):
    skill = "open"
    needs = ("base",)
    work_ms = 2500

    def __init__(self, arena: Arena, truth: Truth, args: dict[str, Any]) -> None:
        super().__init__(arena, truth, args)
        self.door = self._arg("door")

    def check(self) -> str:
        if self.door not in self.arena.doors():
            return f"no door {self.door!r} (doors: {', '.join(self.arena.doors())})"
        if self.arena.place() not in self.arena.door_rooms(self.door):
            return f"{self.door} is not beside {self.arena.place()}"
        return ""

    def finish(self) -> Progress:
        why = self.arena.set_door(self.door, True)
        if why:
            return Progress(1.0, done=True, message=f"{self.door}: {why}")
        return Progress(1.0, done=True, success=True, data={"door": self.door, "open": True})


class Level(Goal):
    skill = "level"
    needs = ("mount",)
    work_ms = 1000

    def finish(self) -> Progress:
        return Progress(1.0, done=True, success=True, data={"level": True})


GOALS: dict[str, type[Goal]] = {g.skill: g for g in (Navigate, Detect, Mark, Open, Level)}


def make_goal(arena: Arena, truth: Truth, skill: str, args: dict[str, Any]) -> Goal:
    """The goal for ``skill``; ``ValueError`` naming what is wrong with the request."""
    cls = GOALS.get(skill)
    if cls is None:
        raise ValueError(f"no skill {skill!r} (skills: {', '.join(GOALS)})")
    return cls(arena, truth, args)
