"""Observations that judge a window of time, held back while what they depend on just changed.

A frequency observer says ``~ok(/map)`` when the rate of ``/map`` *over the last ω seconds*
is wrong. When the input of the node that publishes ``/map`` has just come back
(``ok(/scan)`` again), the window still holds the time without input: for up to ω seconds
``~ok(/map)`` describes the past, and read against the present ``ok(/scan)`` it blames a
healthy node (the clause ``~AB(hector_mapping), ok(/scan) -> ok(/map)``). On the TEDUSAR robot
this made hector_mapping the only diagnosis right after every lidar repair, and the daemon
restarted it (tests/diagnosis/test_lags.py replays the run).

``lags`` maps an atom to the window its observer judges (``observation_lags`` reads it off
the observers: ``lag`` of frequency observers, their window and one message interval more, as
their rate is judged only when a message comes; ``window`` of trend observers, ``within`` of
response observers). ``held_atoms`` names the observed atoms to treat as unknown now:
those whose value was established before the last change of an atom they depend on
(``depends_on``: the positive conditions of the clauses that conclude them, transitively), or
that turned false after it, while that change is younger than their lag (an observer may
notice a silence only after the input came back: the map's silence noticed 0.14 s after the
scan's return still judged the outage; a value that turned true after the change is evidence
at once). Once the lag has passed, the observation is evidence again: a node that is really
broken is diagnosed one lag later, never missed. Without lags nothing is held. Time is passed in;
nothing here reads a clock.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable, Mapping

from host.diagnosis.logic import Theory, ab_component


def observation_lags(observers: Iterable[object]) -> dict[str, float]:
    """``atom -> seconds`` for observers that judge a window (``lag``, ``window`` or
    ``within``)."""
    out: dict[str, float] = {}
    for o in observers:
        lag = (getattr(o, "lag", None) or getattr(o, "window", None)
               or getattr(o, "within", None))
        atoms = getattr(o, "atoms", None)
        if not isinstance(lag, int | float) or lag <= 0 or not callable(atoms):
            continue
        for atom in atoms():
            out[str(atom)] = max(out.get(str(atom), 0.0), float(lag))
    return out


def depends_on(theory: Theory, atoms: Iterable[str]) -> dict[str, frozenset[str]]:
    """For each of ``atoms``: the atoms its concluding clauses need true, transitively."""
    direct: dict[str, set[str]] = {}
    for clause in theory.clauses:
        heads = [x.atom for x in clause.lits if x.positive and ab_component(x.atom) is None]
        if len(heads) != 1:
            continue
        needs = {x.atom for x in clause.lits if not x.positive}
        direct.setdefault(heads[0], set()).update(needs)
    out: dict[str, frozenset[str]] = {}
    for atom in atoms:
        seen: set[str] = set()
        todo = list(direct.get(atom, ()))
        while todo:
            a = todo.pop()
            if a not in seen and a != atom:
                seen.add(a)
                todo.extend(direct.get(a, ()))
        out[atom] = frozenset(seen)
    return out


def held_atoms(lags: Mapping[str, float], inputs: Mapping[str, frozenset[str]],
               since: Callable[[str], float | None], now: float,
               false: Callable[[str], bool] = lambda atom: False) -> tuple[str, ...]:
    """The observed atoms to treat as unknown at ``now`` (see the module docstring);
    ``since(atom)`` is when the atom's current observed value began (None: unknown),
    ``false(atom)`` whether that value is false."""
    held = []
    for atom, lag in lags.items():
        established = since(atom)
        if established is None:
            continue
        for i in inputs.get(atom, ()):
            changed = since(i)
            if changed is not None and now - changed < lag \
                    and (changed > established or false(atom)):
                held.append(atom)
                break
    return tuple(sorted(held))
