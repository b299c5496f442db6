"""The client of the world's skill servers (``emulator.robot.world.server``): goals over TCP.

``WorldClient.connect(url)`` opens one connection (``tcp://host:port``, the ``world:`` line
``dxboard emulate --robot --world`` prints) and a reader task that hands every message to the
goal it belongs to. ``goal(skill, args)`` sends a goal and returns a ``GoalHandle``, whose
``next(timeout)`` gives the goal's messages in order (``accepted``, ``feedback``..., one
``result``; None when nothing came within ``timeout``) and ``cancel()`` asks the world to stop
it. ``state()`` asks for the world's state. A lost connection ends every open goal with a
failed result naming it; ``close()`` is idempotent. Messages are the world's JSON objects as
they are: the skill layer (``host.skills.skill``) interprets them. The wire is
``emulator.jsonlines``'s.
"""

from __future__ import annotations

import asyncio
import contextlib
import itertools
import logging
from typing import Any

from emulator.jsonlines import connect, encode, messages, tcp_address
from host.errors import RemoteError, UserError

log = logging.getLogger(__name__)


class GoalHandle:
    def __init__(self, client: WorldClient, goal_id: str, skill: str) -> None:
        self.client = client
        self.goal_id = goal_id
        self.skill = skill
        self.queue: asyncio.Queue[dict[str, Any]] = asyncio.Queue()
        self.done = False

    async def next(self, timeout: float) -> dict[str, Any] | None:
        """The goal's next message, or None if none came within ``timeout`` seconds."""
        try:
            msg = await asyncio.wait_for(self.queue.get(), timeout)
        except TimeoutError:
            return None
        if msg.get("event") == "result":
            self.done = True
            self.client.goals.pop(self.goal_id, None)
        return msg

    async def cancel(self) -> None:
        """Ask the world to stop the goal (its result, "canceled", follows)."""
        if not self.done:
            await self.client.send({"op": "cancel", "id": self.goal_id})


class WorldClient:
    def __init__(self, reader: asyncio.StreamReader, writer: asyncio.StreamWriter,
                 url: str) -> None:
        self.url = url
        self._reader = reader
        self._writer = writer
        self.goals: dict[str, GoalHandle] = {}
        self._states: list[asyncio.Future[dict[str, Any]]] = []
        self._ids = itertools.count(1)
        self._task = asyncio.ensure_future(self._read())
        self.lost = ""

    @classmethod
    async def connect(cls, url: str, timeout: float = 10.0) -> WorldClient:
        address = tcp_address(url)
        if address is None:
            raise UserError(f"world URL {url!r} is not tcp://HOST:PORT",
                            "give the world: line `dxboard emulate --robot --world` printed")
        try:
            reader, writer = await connect(*address, timeout)
        except (OSError, TimeoutError) as exc:
            raise RemoteError(f"cannot reach the world at {url}: {exc}",
                              "is the emulated robot running with --world?") from None
        return cls(reader, writer, url)

    async def send(self, msg: dict[str, Any]) -> None:
        if self.lost:
            raise RemoteError(f"the world at {self.url} is gone: {self.lost}")
        self._writer.write(encode(msg))
        await self._writer.drain()

    async def goal(self, skill: str, args: dict[str, Any]) -> GoalHandle:
        goal_id = f"{skill}-{next(self._ids)}"
        handle = self.goals[goal_id] = GoalHandle(self, goal_id, skill)
        await self.send({"op": "goal", "id": goal_id, "skill": skill, "args": args})
        return handle

    async def state(self, timeout: float = 5.0) -> dict[str, Any]:
        fut: asyncio.Future[dict[str, Any]] = asyncio.get_running_loop().create_future()
        self._states.append(fut)
        await self.send({"op": "state"})
        return await asyncio.wait_for(fut, timeout)

    async def _read(self) -> None:
        why = "closed by the world"
        try:
            async for msg in messages(self._reader):
                if msg.get("event") == "state" and self._states:
                    self._states.pop(0).set_result(msg["state"])
                elif msg.get("event") == "error":
                    log.warning("the world says: %s", msg.get("error"))
                elif (handle := self.goals.get(str(msg.get("id")))) is not None:
                    handle.queue.put_nowait(msg)
        except (asyncio.IncompleteReadError, ConnectionError, asyncio.LimitOverrunError) as exc:
            why = str(exc) or type(exc).__name__
        self.lost = why
        for handle in list(self.goals.values()):
            handle.queue.put_nowait({"id": handle.goal_id, "event": "result", "status": "failed",
                                     "success": False, "data": {},
                                     "message": f"lost the world: {why}"})
        for fut in self._states:
            if not fut.done():
                fut.set_exception(RemoteError(f"lost the world: {why}"))

    async def close(self) -> None:
        self._task.cancel()
        with contextlib.suppress(asyncio.CancelledError):
            await self._task
        self._writer.transport.abort()
