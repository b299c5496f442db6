"""dxboard as the lifecycle manager of managed nodes it did not start (``external:``).

Nav2's lifecycle manager brings its nodes up in a fixed list and gives up on a node that does
not answer in time. Here each bring-up and repair is a step the repair planner chose (the
repair domain's ``activate_node`` and ``reset_node``: their preconditions order the nodes by
the model's dependencies and the declared ``after``), and a transition is judged by the state
the node reached, not by the call's answer:

    activate  (bring up)   unconfigured: configure, activate; inactive: activate; active: -
    reset     (repair)     active: deactivate, cleanup, configure, activate;
                           inactive: cleanup, configure, activate; unconfigured: configure, activate

``finalized`` has no way back through transitions: the step fails with one line saying so
(the node's restart actuator, ``restart_node``, is the repair then). Each transition is asked
with ``change_state``; when the call times out (a configure that opens a slow device) the
manager asks ``get_state`` until ``settle_s`` has passed, when it says it failed, once:
the transition's goal state reached is a success (a ``change_state`` that timed out but
succeeded), a node still short of it a ``LifecycleError`` naming the node, the transition
and the state it is in.
``watch(node, callback)`` subscribes the node's ``transition_event`` topic: every state it
enters, whoever made the transition (the daemon logs them; the next diagnosis acts on them).
"""

from __future__ import annotations

import asyncio
import contextlib
import logging
import time
from collections.abc import Callable
from typing import Any

from lifecycle_msgs.msg import TransitionEvent

from host.observers.sources.ros2_node import RosNode
from host.ros.lifecycle import TRANSITIONS, LifecycleClient, LifecycleError

log = logging.getLogger(__name__)

SETTLE_S = 30.0  # how long a transition may take to show in get_state after its call
POLL_S = 0.2
GOAL = {"configure": "inactive", "activate": "active", "deactivate": "inactive",
        "cleanup": "unconfigured"}
UP = {"unconfigured": ("configure", "activate"), "inactive": ("activate",), "active": ()}
RESET = {"active": ("deactivate", "cleanup", "configure", "activate"),
         "inactive": ("cleanup", "configure", "activate"),
         "unconfigured": ("configure", "activate")}
assert set(GOAL) == set(TRANSITIONS)


class LifecycleManager:
    def __init__(self, ros: RosNode, call_timeout_s: float = 10.0,
                 settle_s: float = SETTLE_S) -> None:
        self.ros = ros
        self.client = LifecycleClient(ros, call_timeout_s)
        self.settle_s = settle_s
        self._watches: list[Any] = []

    async def activate(self, node: str) -> str:
        """Bring ``node`` up to active from where it is (``activate_node``); what was done."""
        return await self._drive(node, UP, "bring up")

    async def reset(self, node: str) -> str:
        """Back to active through a fresh configure (``reset_node``); what was done."""
        return await self._drive(node, RESET, "reset")

    async def _drive(self, node: str, ways: dict[str, tuple[str, ...]], what: str) -> str:
        await self.client.discovered(node, self.client.timeout_s)
        start = await self._state(node)
        steps = ways.get(start)
        if steps is None:
            raise LifecycleError(f"{node} is {start}: no lifecycle transition leads back to "
                                 "active", "restart its process (external: systemd, command "
                                 "or container)")
        notes = [await self.transition(node, step) for step in steps]
        end = await self._state(node)
        if end != "active":
            raise LifecycleError(f"{node} is {end} after {', '.join(steps)}",
                                 "is its device powered and answering?")
        done = ", ".join(n for n in notes) or "already active"
        return f"{node} {what} from {start}: {done}"

    async def transition(self, node: str, name: str) -> str:
        """Ask for one transition; judge it by the state reached (see the module docstring)."""
        goal = GOAL[name]
        t0 = time.monotonic()
        try:
            await self.client.change(node, name)
            return name
        except LifecycleError as exc:
            why = str(exc)
        # timed out: it may still be busy in the transition; refused: its state now
        state = await (self._settled(node, goal) if _timed_out(why) else self._state(node))
        if state != goal:
            raise LifecycleError(f"{node}: {name} left it {state} ({why})",
                                 "is its device powered and answering?")
        log.info("%s: %s reached %s by get_state after %.1f s although the call said: %s",
                 node, name, goal, time.monotonic() - t0, why)
        return f"{name} (reached {goal} by get_state: the call {_short(why)})"

    async def _settled(self, node: str, goal: str | None) -> str:
        """The node's state once it is ``goal`` (None: any answer), or the last one seen when
        ``settle_s`` is up ("unknown": none)."""
        end = time.monotonic() + self.settle_s
        state = "unknown"
        while True:
            with contextlib.suppress(LifecycleError):  # busy in its transition: ask again
                state = await self.client.state(node)
            if state == goal or (goal is None and state != "unknown") \
                    or time.monotonic() >= end:
                return state
            await asyncio.sleep(POLL_S)

    async def _state(self, node: str) -> str:
        state = await self._settled(node, None)
        if state == "unknown":
            raise LifecycleError(f"{node}: no answer from /{node}/get_state within "
                                 f"{self.settle_s:g} s", "is it running?")
        return state

    def watch(self, node: str, callback: Callable[[str, str], None]) -> None:
        """``callback(node, state)`` on the executor's thread for every transition event."""
        def on(msg: TransitionEvent) -> None:
            callback(node, str(msg.goal_state.label))
        self._watches.append(self.ros.node.create_subscription(
            TransitionEvent, f"/{node}/transition_event", on, 10))


def _timed_out(why: str) -> bool:
    return "no answer" in why  # LifecycleClient's words for a call that timed out


def _short(why: str) -> str:
    return "timed out" if _timed_out(why) else "failed"
