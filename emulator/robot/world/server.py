"""The world's skill servers on TCP, stepped on the emulator's clock (``world: tcp://...``).

Protocol (like a ROS action server, one JSON object per line each way, UTF-8, at most 64 KiB)::

    -> {"op": "goal", "id": ID, "skill": SKILL, "args": {...}}   (emulator.robot.world.skills)
    <- {"id": ID, "event": "accepted"}
    <- {"id": ID, "event": "feedback", "progress": 0..1, "waiting": [symptom, ...],
        "state": STATE}                                          (every FEEDBACK_S while active)
    <- {"id": ID, "event": "result", "status": "succeeded" | "failed" | "rejected" | "canceled",
        "success": bool, "message": "...", "data": {...}, "state": STATE}
    -> {"op": "cancel", "id": ID}              -> the goal's result, status "canceled"
    -> {"op": "state"}                         <- {"event": "state", "state": STATE}
    -> {"op": "door", "door": D, "open": bool}  <- {"event": "door", "door": D, "open": bool,
                                                   "error": "..." when it could not}
       (an exogenous event: a door opens or closes without the robot; for experiments;
       "locked": bool as well locks or unlocks it: a locked door does not open)
    -> {"op": "jam"}                           <- {"event": "jam"}
       (a fault of the marker dispenser: the next mark reports success and leaves nothing)

``STATE`` is ``{"t_ms", "pose": [x, y, yaw], "place": room or door, "room": the room, or in a
doorway the nearer of its two rooms, "doors": {name: open}, "locked": [door, ...],
"marked": [victim, ...]}``.
The robot does one skill at a time: a new goal preempts the active
one (its result: "canceled"). A bad line gets ``{"event": "error", "error": "..."}`` and
changes nothing. Results and feedback go to the connection that sent the goal; a goal whose
connection closes is canceled. Planning runs in a worker thread, so the emulator's loop (which
also runs the firmware and the devices) never waits for it.
"""

from __future__ import annotations

import asyncio
import contextlib
import logging
from collections.abc import Callable
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass
from typing import Any

from emulator.jsonlines import MAX_LINE, Lines, send
from emulator.robot.world.arena import Arena
from emulator.robot.world.skills import Goal, Progress, make_goal
from emulator.robot.world.truth import Truth

log = logging.getLogger(__name__)

STEP_S = 0.05
FEEDBACK_S = 0.2


@dataclass
class Active:
    goal_id: str
    goal: Goal
    writer: asyncio.StreamWriter
    last_feedback: float = 0.0


class WorldServer:
    def __init__(self, arena: Arena, truth: Truth, now_ms: Callable[[], int],
                 host: str = "127.0.0.1") -> None:
        self.arena = arena
        self.truth = truth
        self.now_ms = now_ms
        self.host = host
        self.port = 0
        self.active: Active | None = None
        self._server: asyncio.Server | None = None
        self._task: asyncio.Task[None] | None = None
        self._preparing: asyncio.Task[None] | None = None
        self._lines = self._requests()
        self._planner = ThreadPoolExecutor(1, thread_name_prefix="world-planner")  # one at a time

    @property
    def url(self) -> str:
        return f"tcp://{self.host}:{self.port}"

    async def start(self) -> str:
        self._server = await asyncio.start_server(self._lines.serve, self.host, 0,
                                                  limit=MAX_LINE)
        self.port = self._server.sockets[0].getsockname()[1]
        self._task = asyncio.get_running_loop().create_task(self._run())
        return self.url

    async def stop(self) -> None:
        for task in (self._task, self._preparing):
            if task is not None:
                task.cancel()
                with contextlib.suppress(asyncio.CancelledError):
                    await task
        if self._server is not None:
            self._server.close()
            self._server = None
        self._planner.shutdown(wait=False, cancel_futures=True)

    def state(self) -> dict[str, Any]:
        return {"t_ms": self.now_ms(), **self.arena.state()}

    # --- stepping ---------------------------------------------------------------------------

    async def _run(self) -> None:
        loop = asyncio.get_running_loop()
        while True:
            await asyncio.sleep(STEP_S)
            act = self.active
            if act is None or (self._preparing is not None and not self._preparing.done()):
                continue
            try:
                prog = act.goal.step(self.now_ms())
            except Exception as exc:  # a bug in a skill must not stop the world
                log.exception("skill %s failed", act.goal.skill)
                prog = Progress(act.goal.fraction(), done=True, message=f"internal error: {exc}")
            if prog.done:
                self.active = None
                self._send(act.writer, self._result(act.goal_id, prog))
            elif loop.time() - act.last_feedback >= FEEDBACK_S:
                act.last_feedback = loop.time()
                self._send(act.writer, {"id": act.goal_id, "event": "feedback",
                                        "progress": prog.progress, "waiting": list(prog.waiting),
                                        "state": self.state()})

    def _result(self, goal_id: str, prog: Progress, status: str = "") -> dict[str, Any]:
        status = status or ("succeeded" if prog.success else "failed")
        return {"id": goal_id, "event": "result", "status": status, "success": prog.success,
                "message": prog.message, "data": prog.data, "state": self.state()}

    # --- requests ---------------------------------------------------------------------------

    def _requests(self) -> Lines:
        def cancel(msg: dict[str, Any], writer: Any) -> dict[str, Any] | None:
            if self.active is None or self.active.goal_id != msg.get("id"):
                return _error(f"no active goal {msg.get('id')!r}")
            self._cancel("canceled by the client")
            return None

        def jam(msg: dict[str, Any], writer: Any) -> dict[str, Any]:
            self.arena.jammed = True
            return {"event": "jam"}

        return Lines({"goal": self._goal, "cancel": cancel,
                      "state": lambda msg, writer: {"event": "state", "state": self.state()},
                      "door": lambda msg, writer: self._door(msg), "jam": jam},
                     error=_error, max_line=MAX_LINE, on_close=self._gone)

    def _gone(self, writer: Any) -> None:
        if self.active is not None and self.active.writer is writer:
            self._cancel("the client went away")

    def _request(self, line: bytes, writer: Any) -> Any:
        """The reply to one request line (None: nothing to say at once)."""
        return self._lines.answer(line, writer)

    def _goal(self, msg: dict[str, Any], writer: asyncio.StreamWriter) -> dict[str, Any] | None:
        goal_id, skill, args = msg.get("id"), msg.get("skill"), msg.get("args", {})
        if not isinstance(goal_id, str) or not isinstance(skill, str) \
                or not isinstance(args, dict):
            return _error('a goal is {"op": "goal", "id": "...", '
                    '"skill": "...", "args": {...}}')
        try:
            goal = make_goal(self.arena, self.truth, skill, args)
            why = goal.check()
        except ValueError as exc:
            why = str(exc)
        if why:
            return self._result(goal_id, Progress(0.0, done=True, message=why), "rejected")
        if self.active is not None:
            self._cancel(f"preempted by {skill}")
        self.active = Active(goal_id, goal, writer)
        self._send(writer, {"id": goal_id, "event": "accepted"})
        self._preparing = asyncio.get_running_loop().create_task(self._prepare(goal))
        return None

    async def _prepare(self, goal: Goal) -> None:
        loop = asyncio.get_running_loop()
        try:
            await goal.prepare(lambda fn: loop.run_in_executor(self._planner, fn))
        except Exception as exc:  # a bug in a skill must not stop the world
            log.exception("preparing %s failed", goal.skill)
            goal.failed = f"internal error: {exc}"

    def _cancel(self, why: str) -> None:
        act, self.active = self.active, None
        if act is None:
            return
        if self._preparing is not None and not self._preparing.done():
            self._preparing.cancel()
        self._send(act.writer, self._result(
            act.goal_id, Progress(act.goal.fraction(), done=True, message=why), "canceled"))

    def _door(self, msg: dict[str, Any]) -> dict[str, Any]:
        door, open_, locked = msg.get("door"), msg.get("open"), msg.get("locked")
        if not isinstance(door, str) or not isinstance(open_, bool) \
                or not isinstance(locked, bool | None):
            return _error('door needs "door": NAME and "open": true|false '
                          '(and may give "locked": true|false)')
        try:
            why = self.arena.set_door(door, open_)
            if locked is not None and not why:
                why = self.arena.set_lock(door, locked)
        except ValueError as exc:
            return _error(str(exc))
        reply: dict[str, Any] = {"event": "door", "door": door, "open": self.arena.doors()[door]}
        if why:
            reply["error"] = why
        return reply

    @staticmethod
    def _send(writer: asyncio.StreamWriter, msg: dict[str, Any]) -> None:
        send(writer, msg)


def _error(words: str) -> dict[str, Any]:
    return {"event": "error", "error": words}
