"""Protected components: never switched off, whatever the domain file says.

The tedusar domain guards ``shutdown``, ``power_cycle`` and ``stop_node`` with ``(not
(protected ?c))``, but a hand-written or edited domain may not, and the PC that runs this
very host must stay powered. So the problem layer enforces it again on the ground task: an
operator is removed when it is one of the switch-off actions applied to a protected object,
or when any of its effects (conditional ones included) makes ``on(p)`` or ``running(p)``
false for a protected ``p`` — in the domain's own words (``vocabulary``): a powered or running
predicate made false, or its explicit complement (the original domain's ``not_on``) made
true. The removed operators are recorded in ``Task.removed`` with the
reason, so a goal that only they could reach is reported as such; ``check_plan`` re-checks
any plan, from any planner, before it is handed out.
"""

from __future__ import annotations

from collections.abc import Iterable

from host.planning.errors import NoPlanError
from host.planning.task import GroundOp, Task
from host.planning.vocabulary import Vocabulary

SWITCH_OFF_ACTIONS = frozenset({"shutdown", "power_cycle", "stop_node", "power_down"})


def switches_off(task: Task, op: GroundOp, protected: frozenset[str],
                 words: Vocabulary | None = None) -> str | None:
    """Why ``op`` would switch off a protected object, or None."""
    words = Vocabulary() if words is None else words
    if op.name in SWITCH_OFF_ACTIONS:
        hit = [a for a in op.args if a in protected]
        if hit:
            return f"{op.label()} switches off protected {hit[0]}"
    for x in op.effect_literals():
        pred, args = task.atoms[x >> 1]
        if words.switched_off(pred, bool(x & 1)) and any(a in protected for a in args):
            made = "true" if x & 1 else "false"
            return f"{op.label()} makes {pred}({','.join(args)}) {made} on a protected component"
    return None


def enforce(task: Task, protected: Iterable[str], words: Vocabulary | None = None) -> Task:
    """The task without the operators that switch off protected components."""
    prot = frozenset(protected)
    if not prot:
        return task
    kept: list[GroundOp] = []
    removed = list(task.removed)
    for op in task.ops:
        why = switches_off(task, op, prot, words)
        if why is None:
            kept.append(op)
        else:
            removed.append((op.label(), why))
    return Task(task.atoms, task.index, kept, removed)


def check_plan(task: Task, ops: Iterable[GroundOp], protected: Iterable[str],
               words: Vocabulary | None = None) -> None:
    """Raise ``NoPlanError`` if a plan step switches off a protected component."""
    prot = frozenset(protected)
    for op in ops:
        why = switches_off(task, op, prot, words)
        if why is not None:
            raise NoPlanError(
                f"the plan was rejected: {why}",
                "protected components are never switched off; repair them by hand",
            )
