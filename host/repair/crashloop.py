"""Nodes that die at once after every start: their device is the suspect, not the node.

A driver that exits as soon as it starts because its device is off or absent is, to the
diagnosis, a node that does not run, and the node alone explains that (``~AB(n) ->
running(n)``): its restart was planned again and again until the attempt limiter quarantined
the node, while the device — switched off by a person and held, or a USB device the board
cannot switch — was never the suspect (issue 28, item 1). But a node's observations depend on
its device (the model's driver -> hardware dependency), so a node that keeps dying within its
settle time is evidence against the device as much as against the node.

``CrashLoops(observations, settle, nodes, stops, stretch)`` listens to the observation set and
notes, for each node, how long each of its runs lasted (``running(n)`` true, then false; a run
that a ``stop_node`` of this host ended, ``stops``, is no crash and is not noted). A node whose
last ``CRASHES`` runs each ended within its settle time (at least ``SHORT_S``), stretched as the
executor stretches it on a busy machine (``stretch``, read when the run ended: a process starts
that many times slower), and that is not running now *loops*. ``blame_devices`` then changes
each candidate diagnosis that blames a looping node: the node's devices whose observations
are not all good (``on`` and, with a current band, ``in_band``: a device known powered and
drawing its current is not the cause) join the candidate, so the device is repaired first
(switched on, power-cycled) and the node's restart follows in the same plan. A device that
cannot be repaired here — held by a person, quarantined, or not on a board channel — takes
the node's place: the node is not restarted while its device cannot be brought back, and a
note says so. A run that lasts longer than the settle time ends the loop, and so does
``RETRY_S`` without a death (nothing may tell that a device off the board is back: the node
is tried again then).

A node whose device is *quarantined* and not good is not restarted either, loop or not: the
daemon has given up on the device (its repairs failed, it is in its safe state, off), so a
restart cannot bring the node's outputs back, and it would spend the node's own repair
attempts until the node is quarantined too, for its device's fault (a driver that exits as
its device's switch fails off, restarted once the device is quarantined). The device takes the
node's place until a person clears it; then both are repaired. Pure bookkeeping: times are the
observations'.
"""

from __future__ import annotations

from collections import deque
from collections.abc import Callable, Collection, Iterable, Mapping
from dataclasses import dataclass

from host.diagnosis.model import SystemModel
from host.diagnosis.observations import ObservationSet
from host.repair.policy import Candidate

CRASHES = 2  # this many short runs in a row make a loop
SHORT_S = 5.0  # a run this short (or within the node's settle time) ended at once
RETRY_S = 300.0  # a loop this old is over: the node is started once more


@dataclass(frozen=True)
class Loop:
    """``node``'s last runs, each at most ``longest`` seconds long."""

    node: str
    runs: int
    longest: float

    def text(self) -> str:
        return f"{self.node}: exits at once after each start ({self.runs} runs of at most " \
               f"{self.longest:.1f} s)"


class CrashLoops:
    def __init__(self, observations: ObservationSet, settle: Mapping[str, float],
                 nodes: Iterable[str], stops: Mapping[str, float] | None = None,
                 stretch: Callable[[], float] = lambda: 1.0) -> None:
        self.observations = observations
        self.settle = settle
        self.stops = {} if stops is None else stops  # node -> our latest stop_node
        self.stretch = stretch
        # node -> its latest runs: (when it ended, how long it lasted, the longest a run of
        # that moment could last and still be a crash)
        self._runs: dict[str, deque[tuple[float, float, float]]] = {
            n: deque(maxlen=CRASHES) for n in nodes}
        self._up: dict[str, float] = {}  # node -> when its current run began
        observations.listen(self._changed)

    def _changed(self) -> None:
        for node, runs in self._runs.items():
            obs = self.observations.get(f"running({node})")
            since = self.observations.since(f"running({node})")
            if obs is None or since is None:
                continue
            if obs.literal.positive:
                self._up.setdefault(node, since)
            elif node in self._up:
                up = self._up.pop(node)
                if self.stops.get(node, up - 1.0) < up:  # not ended by a stop of ours
                    short = max(SHORT_S, self.settle.get(node, 0.0)) * max(1.0, self.stretch())
                    runs.append((since, since - up, short))

    def looping(self, node: str, now: float | None = None) -> Loop | None:
        """The loop ``node`` is in at ``now``, None when it is not in one (or runs now)."""
        runs = self._runs.get(node)
        if not runs or len(runs) < CRASHES or node in self._up:
            return None
        if now is not None and now - runs[-1][0] > RETRY_S:
            return None
        if any(length > short for _, length, short in runs):
            return None
        return Loop(node, len(runs), max(length for _, length, _ in runs))


def _good(device: str, model: SystemModel, observations: ObservationSet) -> bool:
    """Known powered and, with a current band, drawing its current."""
    atoms = [f"on({device})"]
    if model.components[device].current is not None:
        atoms.append(f"in_band({device})")
    for atom in atoms:
        obs = observations.get(atom)
        if obs is None or not obs.literal.positive:
            return False
    return True


def _why(device: str, unavailable: Collection[str]) -> str:
    return "is held or quarantined" if device in unavailable else "is not on a board channel"


def blame_devices(cands: Iterable[Candidate], loops: CrashLoops, model: SystemModel,
                  observations: ObservationSet,
                  unavailable: Collection[str],
                  now: float | None = None,
                  quarantined: Collection[str] = ()) -> tuple[list[Candidate], list[str]]:
    """The candidates with the devices of their looping nodes, and the quarantined devices of
    their nodes, blamed (see the module), and one note per such node; ``unavailable``: the held
    and quarantined components, ``quarantined``: the quarantined ones."""
    out: list[Candidate] = []
    notes: dict[str, str] = {}
    for c in cands:
        bad = set(c.bad)
        for node in sorted(c.bad):
            loop = loops.looping(node, now)
            comp = model.components.get(node)
            if comp is None:
                continue
            suspects = [h for h in comp.hardware if not _good(h, model, observations)]
            gone = [h for h in suspects if h in quarantined]
            if loop is None and gone:
                bad.discard(node)
                bad |= set(gone)
                names = ", ".join(gone)
                notes[node] = (f"{node}: its device {names} is quarantined and not working: "
                               f"{node} is not restarted until {names} is back")
                continue
            if loop is None or not suspects:
                continue
            bad |= set(suspects)
            stuck = [h for h in suspects
                     if h in unavailable or model.components[h].channel is None]
            if stuck:
                bad.discard(node)
                why = "; ".join(f"{h} {_why(h, unavailable)}" for h in stuck)
                notes[node] = (f"{loop.text()}: its device is the suspect, and {why}: "
                               f"{node} is not restarted until {', '.join(stuck)} is back")
            else:
                notes[node] = (f"{loop.text()}: its device {', '.join(suspects)} is the suspect: "
                               f"repaired first, then {node} restarted")
        cand = Candidate(frozenset(bad), c.probability)
        if cand.bad not in [o.bad for o in out]:
            out.append(cand)
    return out, list(notes.values())
