"""Plans as partial orders: steps, the orderings between them, and what is ready to run.

A planner returns a sequence; the executor should not have to run it as one. ``deorder``
turns a valid sequence into a partial order: step ``j`` waits for an earlier step ``i``
exactly when the two *interfere* (one writes an atom the other reads, as precondition or as
condition of a conditional effect, or writes), directly or through other steps. Steps that
do not interfere commute, so every linearization of the partial order reaches the same state
as the planner's sequence: the plan stays valid whichever independent steps run first.
``Plan.after`` keeps the transitive reduction (the direct predecessors); ``ready(done)``
gives the steps an executor may start now, ``layers()`` the steps grouped into rounds that
could run in parallel (the executor still spaces switch-ons on the board). Plans are plain
values: ``to_json`` is the ``dxboard plan --json`` format.

``stops_first`` reorders a valid sequence before that: a driver is stopped *before* its
device's power cycle, not after it. Both orders are valid and cost the same, but after the
cycle the stop (and so the driver's restart) waits until the device's boot is verified,
while before it the stop takes a moment and the restart begins as soon as the device is back
on, its driver connecting while the device boots (issue 18: a hung lidar's repair).
"""

from __future__ import annotations

from collections.abc import Collection, Sequence
from dataclasses import dataclass, field
from typing import Any

from host.planning.task import GroundOp, holds

#: a ``stop_node`` moves ahead of these steps (``stops_first``)
STOP_BEFORE = frozenset({"power_cycle"})


@dataclass(frozen=True)
class Step:
    """One action of a plan; ``id`` is its position in the planner's sequence."""

    id: int
    action: str
    args: tuple[str, ...]

    def __str__(self) -> str:
        return f"{self.action}({', '.join(self.args)})"


@dataclass(frozen=True)
class Plan:
    """A partially ordered plan. ``steps`` is a valid linearization; ``after[j]`` holds the
    ids of the steps that must finish before step ``j`` starts (direct predecessors only)."""

    steps: tuple[Step, ...]
    after: tuple[frozenset[int], ...]
    cost: float = 0.0
    planner: str = ""
    notes: tuple[str, ...] = field(default=(), compare=False)

    def __len__(self) -> int:
        return len(self.steps)

    def ready(self, done: Collection[int], started: Collection[int] = ()) -> list[Step]:
        """Steps not yet done or started whose predecessors are all done."""
        return [
            s
            for s in self.steps
            if s.id not in done and s.id not in started and self.after[s.id] <= set(done)
        ]

    def layers(self) -> list[list[Step]]:
        """Rounds of steps: each round depends only on earlier rounds."""
        level: dict[int, int] = {}
        for s in self.steps:  # steps is a linearization: predecessors come first
            level[s.id] = 1 + max((level[p] for p in self.after[s.id]), default=-1)
        out: list[list[Step]] = [[] for _ in range(max(level.values(), default=-1) + 1)]
        for s in self.steps:
            out[level[s.id]].append(s)
        return out

    def orderings(self) -> list[tuple[int, int]]:
        """``(before, after)`` pairs of the transitive reduction."""
        return [(i, s.id) for s in self.steps for i in sorted(self.after[s.id])]

    def to_json(self) -> dict[str, Any]:
        return {
            "plan": [
                {"id": s.id, "action": s.action, "args": list(s.args),
                 "after": sorted(self.after[s.id])}
                for s in self.steps
            ],
            "cost": self.cost,
            "planner": self.planner,
            "layers": [[s.id for s in layer] for layer in self.layers()],
            "notes": list(self.notes),
        }

    def __str__(self) -> str:
        return ", ".join(str(s) for s in self.steps)


def deorder(
    ops: Sequence[GroundOp], cost: float = 0.0, planner: str = "", notes: Sequence[str] = ()
) -> Plan:
    """The partial order of a valid sequence of ground operators (see module docstring)."""
    # Per atom, the last step that wrote it and the steps that read it since: ordering after
    # those is enough, every other interference follows through the chain of writers.
    last_writer: dict[int, int] = {}
    readers: dict[int, list[int]] = {}
    reach: list[int] = []  # bit i of reach[j]: step i precedes step j (transitively)
    after: list[frozenset[int]] = []
    for j, op in enumerate(ops):
        reads, writes = op.read_atoms(), op.write_atoms()
        preds = {last_writer[a] for a in reads | writes if a in last_writer}
        for a in writes:
            preds.update(readers.get(a, ()))
        preds.discard(j)
        implied = 0
        for i in preds:
            implied |= reach[i]
        direct = frozenset(i for i in preds if not implied >> i & 1)
        mask = implied
        for i in direct:
            mask |= 1 << i
        reach.append(mask)
        after.append(direct)
        for a in reads:
            readers.setdefault(a, []).append(j)
        for a in writes:
            last_writer[a] = j
            readers[a] = []
    steps = tuple(Step(k, op.name, op.args) for k, op in enumerate(ops))
    return Plan(steps, tuple(after), cost, planner, tuple(notes))


def _valid(ops: Sequence[GroundOp], init: int, goal: Sequence[int]) -> bool:
    state = init
    for op in ops:
        if not op.applicable(state):
            return False
        state = op.apply(state)
    return all(holds(x, state) for x in goal)


def stops_first(ops: Sequence[GroundOp], init: int, goal: Sequence[int]) -> list[GroundOp]:
    """``ops`` (valid from ``init`` to ``goal``) with every ``stop_node`` moved ahead of the
    ``STOP_BEFORE`` steps just before it, wherever the sequence stays valid."""
    out = list(ops)
    for j in range(len(out)):
        k = j
        while (k > 0 and out[k].name == "stop_node" and out[k - 1].name in STOP_BEFORE
               and _valid(swapped := [*out[:k - 1], out[k], out[k - 1], *out[k + 1:]],
                          init, goal)):
            out, k = swapped, k - 1
    return out
