"""Components still booting: switched on or started by something other than a repair step.

A device the board switched back on by itself (after an input under-voltage, issue 25 item 7)
or a node a freshly started daemon brought up has not yet had its settle time — the boot time
the model gives it — and its topics are silent for that reason alone. A repair that judged
them then would power-cycle a device that is just booting. ``booting(observations, settle,
now)`` is the pure rule: every component whose ``on(device)`` or ``running(node)`` turned true
less than its settle time ago (a node's stretched on a busy machine, as the executor stretches
a start step's), with the seconds it has left (a repair step's own switch-ons and starts have
waited their settle by the time the loop looks again, so they never show here).
The repair service waits for them as it waits for the board's own protection, at most
``MAX_WAIT_FACTOR`` times the longest settle time, so that a component that keeps coming
back on cannot hold every repair off.

``came_back(...)``: the devices that came on without a switch-on of this host (the board
restored them, or they were on when the daemon started) and have booted since. Their power is
not what is wrong: when another diagnosis explains what is seen, the repair service leaves out
the diagnoses that blame them, so that their drivers are restarted instead of the devices
power-cycled once more.
"""

from __future__ import annotations

from collections.abc import Iterable, Mapping

from host.diagnosis.observations import ObservationSet

MAX_WAIT_FACTOR = 2.0


def up_atom(name: str, is_node: bool) -> str:
    """The atom that says ``name`` is up: ``running(node)`` or ``on(device)``."""
    return f"running({name})" if is_node else f"on({name})"


def up_since(observations: ObservationSet, atom: str) -> float | None:
    """When ``atom`` turned true, None while it is false or unknown."""
    obs = observations.get(atom)
    return None if obs is None or not obs.literal.positive else observations.since(atom)


def booting(observations: ObservationSet, settle: Mapping[str, float],
            components: Iterable[tuple[str, bool]], now: float,
            stretch: float = 1.0) -> dict[str, float]:
    """``{component: seconds left}`` for those up for less than their settle time;
    ``components`` are (name, is_node) pairs. On a machine busy ``stretch`` times over a
    node's settle time is that many times longer (a process starts slower, as the executor
    stretches a start step's); a device boots in its own time."""
    out: dict[str, float] = {}
    for name, is_node in components:
        since = up_since(observations, up_atom(name, is_node))
        if since is None:
            continue
        left = since + settle.get(name, 0.0) * (max(1.0, stretch) if is_node else 1.0) - now
        if left > 0:
            out[name] = left
    return out


def describe(left: Mapping[str, float]) -> str:
    """The note's reason: ``hokuyo, jaguar just came up: booting (up to 1.5 s more)``."""
    return f"{', '.join(sorted(left))} just came up: booting (up to {max(left.values()):.1f} " \
           "s more)"


CAME_BACK_S = 20.0  # how long after its settle a device the board restored counts as restored
OURS_S = 5.0  # a switch-on of ours that long before the device came on is what switched it


def came_back(observations: ObservationSet, settle: Mapping[str, float],
              devices: Iterable[tuple[str, int]], commands: Iterable[tuple[float, int, bool]],
              now: float) -> set[str]:
    """The devices (name, channel) that came back on less than their settle time plus
    ``CAME_BACK_S`` ago without a switch-on of ours (``commands``: (time, channel, on), the
    actuators' record): the board restored them. Their power is fine — a silent topic now is
    their driver's, which lost its device (issue 25, item 7: a brown-out's devices were
    power-cycled again)."""
    ons = [(t, ch) for t, ch, on in commands if on]
    out = set()
    for name, ch in devices:
        since = up_since(observations, up_atom(name, False))
        if since is None or now - since > settle.get(name, 0.0) + CAME_BACK_S:
            continue
        if not any(c == ch and since - OURS_S <= t <= since + 0.5 for t, c in ons):
            out.add(name)
    return out
