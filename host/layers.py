"""The layer contract of paper 001 (§III, figure 2), the one module every layer uses.

The robot is layered: 0 components (the daemon: observers, SAT diagnosis, repair), 1 skills
(``host.skills``), 2 the executive (``host.executive``: a behaviour tree per mission action),
3 the mission (``host.mission``: knowledge base, temporal planner, dispatcher). Between layer
*i + 1* and layer *i* pass only these values:

- ``Command`` — down: what layer *i + 1* asks of layer *i*, in layer *i*'s words once φ
  (``Concretize``) has turned it from L_{i+1} into L_i (a PDDL action becomes a tree, a tree's
  leaf becomes a skill goal);
- ``LayerObservation`` — up: a fact of layer *i* that layer *i + 1* may use for monitoring, once ψ
  (``Abstract``) has put it in L_{i+1} (the world's state becomes PDDL atoms);
- ``Result`` — up, once per command: ⟨s, Δ⟩ with ``success`` for s and ``explanation`` for Δ,
  a chain of ``Cause``s, each in the words of the layer that found it, the lowest last. A cause
  names the components of layer 0 it blames, so that a mission step that failed because the
  lidar hung says so at every layer above. A reported success is not trusted blindly: the
  layer above checks it against its wider context (the mission layer senses after every action).

Each layer handles what it can (layer 0 repairs, layer 2 holds and retries) and passes up only
what it cannot. Everything here is a frozen value that serialises to plain JSON, so the journal
keeps the results of every layer (``host.events.LayerResult``).
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any, Protocol

COMPONENTS, SKILLS, EXECUTIVE, MISSION = 0, 1, 2, 3
LAYER_NAMES = {COMPONENTS: "components", SKILLS: "skills", EXECUTIVE: "executive",
               MISSION: "mission"}


@dataclass(frozen=True)
class Command:
    """What a layer is asked to do, in its own language: a name and its arguments."""

    layer: int
    name: str
    args: tuple[str, ...] = ()
    params: Mapping[str, str] = field(default_factory=dict)  # named arguments (skill goals)

    def __str__(self) -> str:
        return f"{self.name}({', '.join(self.args)})"


@dataclass(frozen=True)
class LayerObservation:
    """A fact seen at ``layer``: ``fact`` names it, ``value`` is plain JSON."""

    layer: int
    fact: str
    value: Any
    source: str = ""


@dataclass(frozen=True)
class Cause:
    """One step of an explanation Δ: what ``layer`` found (``what``), and the components of
    layer 0 it blames (empty when no component is to blame: a world fact, a plan's fault)."""

    layer: int
    what: str
    components: tuple[str, ...] = ()

    def to_json(self) -> dict[str, Any]:
        return {"layer": self.layer, "what": self.what, "components": list(self.components)}

    @classmethod
    def from_json(cls, data: Mapping[str, Any]) -> Cause:
        return cls(int(data["layer"]), str(data["what"]),
                   tuple(str(c) for c in data.get("components", ())))

    def __str__(self) -> str:
        blame = f" [{', '.join(self.components)}]" if self.components else ""
        return f"{LAYER_NAMES.get(self.layer, self.layer)}: {self.what}{blame}"


@dataclass(frozen=True)
class Result:
    """⟨s, Δ⟩: ``success`` and the explanation, highest layer first; ``data`` is what the layer
    observed at the end (plain JSON), for the layer above to check."""

    success: bool
    explanation: tuple[Cause, ...] = ()
    data: Mapping[str, Any] = field(default_factory=dict)

    @classmethod
    def ok(cls, data: Mapping[str, Any] | None = None) -> Result:
        return cls(True, (), dict(data or {}))

    @classmethod
    def fail(cls, layer: int, what: str, components: Sequence[str] = (),
             below: Result | None = None, data: Mapping[str, Any] | None = None) -> Result:
        """A failure found at ``layer``, on top of the explanation of the layer below."""
        chain = (Cause(layer, what, tuple(sorted(set(components)))),
                 *(below.explanation if below is not None else ()))
        merged = {**(below.data if below is not None else {}), **(data or {})}
        return cls(False, chain, merged)

    def components(self) -> list[str]:
        """Every component of layer 0 the explanation blames, in order, once each."""
        out: list[str] = []
        for cause in self.explanation:
            out += [c for c in cause.components if c not in out]
        return out

    def describe(self) -> str:
        if self.success:
            return "success"
        return "fail: " + "; because ".join(str(c) for c in self.explanation)

    def to_json(self) -> dict[str, Any]:
        return {"success": self.success,
                "explanation": [c.to_json() for c in self.explanation],
                "data": dict(self.data)}

    @classmethod
    def from_json(cls, data: Mapping[str, Any]) -> Result:
        return cls(bool(data["success"]),
                   tuple(Cause.from_json(c) for c in data.get("explanation", ())),
                   dict(data.get("data", {})))


Concretize = Callable[[Command], Sequence[Command]]  # φ: L_{i+1} -> L_i
Abstract = Callable[[LayerObservation], Sequence[LayerObservation]]  # ψ: L_i -> L_{i+1}


class Layer(Protocol):
    """A layer's decision making and execution, as the layer above sees it."""

    level: int

    async def execute(self, command: Command) -> Result:
        """Carry out ``command`` (already in this layer's language) and say how it went."""
        ...
