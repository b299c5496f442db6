"""What the executor believes about the robot: the latest observation of each atom, and waits.

The executor does not believe an action worked because the actuator returned: it waits for
*fresh* observations that show the intended effect (paper 000 §IV-E: "a better strategy ...
would be to wait until the effects have been established"). ``Beliefs`` is that interface::

    ok = await beliefs.wait_for({"on(jaguar)": True, "running(jaguar_node)": True},
                                newer_than=t, timeout=5.0)

is True once, for every atom, the latest observation of it has the wanted value *and* was
made after ``newer_than`` (an observation from before the step proves nothing, nor does a
refresh of the old value); False when ``timeout`` seconds pass first. Unknown (retracted or
never observed) is not the wanted value.

``ObservedBeliefs`` implements it as a waiter on the daemon's one observation set
(``host.diagnosis.observations.ObservationSet``, which the diagnoser diagnoses too): it keeps no
copy; the set calls it on every add, refresh, retraction and expiry, and the waiters are woken.
Observation times are the observers' clock: ``newer_than`` must come from the same monotonic
clock (the executor's ``clock``). Observers repeat unchanged literals every ``refresh`` seconds
with a new time, so a steady state is seen as fresh within one refresh period; an observation
that expired is unknown here as it is to the diagnoser.
"""

from __future__ import annotations

import asyncio
import contextlib
from collections.abc import Mapping
from typing import Protocol

from host.diagnosis.observations import Observation, ObservationSet


class Beliefs(Protocol):
    async def wait_for(self, expected: Mapping[str, bool], newer_than: float,
                       timeout: float, abort: Mapping[str, bool] | None = None,
                       abort_after: float | None = None) -> bool:
        """True once every atom's latest observation is newer than ``newer_than`` and has
        the expected value; False after ``timeout`` seconds, or at once when an atom of
        ``abort`` is observed with its value after ``abort_after`` (default ``newer_than``)."""
        ...

    def value(self, atom: str) -> bool | None:
        """The atom's latest observed value (None: unknown)."""
        ...

    def missing(self, expected: Mapping[str, bool], newer_than: float) -> dict[str, str]:
        """The atoms not (yet) as expected, each with what is known of it instead."""
        ...


class ObservedBeliefs:
    """``Beliefs`` over an ``ObservationSet`` (see the module docstring)."""

    def __init__(self, observations: ObservationSet) -> None:
        self.observations = observations
        self._changed = asyncio.Condition()
        self._pending = False
        observations.listen(self._wake)

    def _wake(self) -> None:
        if self._pending:
            return
        self._pending = True

        async def notify() -> None:
            self._pending = False
            async with self._changed:
                self._changed.notify_all()

        with contextlib.suppress(RuntimeError):  # no running loop: nobody can be waiting
            asyncio.get_running_loop().create_task(notify())

    # -- queries ---------------------------------------------------------------------------
    def value(self, atom: str) -> bool | None:
        o = self.observations.get(atom)
        return None if o is None else o.literal.positive

    def observation(self, atom: str) -> Observation | None:
        return self.observations.get(atom)

    def missing(self, expected: Mapping[str, bool], newer_than: float) -> dict[str, str]:
        """The atoms not (yet) as expected, each with what is known of it instead."""
        out: dict[str, str] = {}
        for atom, want in expected.items():
            o = self.observations.get(atom)
            if o is None:
                out[atom] = "unknown"
            elif o.literal.positive != want:
                out[atom] = f"{'true' if o.literal.positive else 'false'} ({o.source})"
            elif o.time <= newer_than:
                out[atom] = f"not observed again since the step ({o.source})"
        return out

    def holds(self, expected: Mapping[str, bool], newer_than: float) -> bool:
        return not self.missing(expected, newer_than)

    def contradicted(self, abort: Mapping[str, bool], newer_than: float) -> bool:
        """An atom of ``abort`` has been observed with its value after ``newer_than``."""
        for atom, value in abort.items():
            o = self.observations.get(atom)
            if o is not None and o.literal.positive == value and o.time > newer_than:
                return True
        return False

    async def wait_for(self, expected: Mapping[str, bool], newer_than: float,
                       timeout: float, abort: Mapping[str, bool] | None = None,
                       abort_after: float | None = None) -> bool:
        stop = abort or {}
        since = newer_than if abort_after is None else abort_after
        try:
            async with asyncio.timeout(max(0.0, timeout)), self._changed:
                await self._changed.wait_for(
                    lambda: self.holds(expected, newer_than) or self.contradicted(stop, since))
        except TimeoutError:
            pass
        return self.holds(expected, newer_than) and not self.contradicted(stop, since)
