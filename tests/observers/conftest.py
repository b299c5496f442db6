"""Shared helpers for the observer tests: a zenoh endpoint, a simulated observation set."""

from __future__ import annotations

import sys
from pathlib import Path

import pytest

from host.diagnosis.observations import ObservationSet
from host.observers import Update, apply_updates
from tests.ports import zenoh_endpoint

ROOT = Path(__file__).resolve().parents[2]
TEDUSAR = ROOT / "models" / "tedusar"
PYTHON = sys.executable


@pytest.fixture
def endpoint() -> str:
    return zenoh_endpoint()


class Recorder:
    """The sink of a hub in tests: every update in order, and the set they build."""

    def __init__(self) -> None:
        self.updates: list[Update] = []
        self.set = ObservationSet()

    def __call__(self, updates: list[Update]) -> None:
        self.updates.extend(updates)
        apply_updates(updates, self)

    def observe(self, obs: object) -> bool:
        from host.diagnosis.observations import Observation
        assert isinstance(obs, Observation)
        return self.set.add(obs)

    def retract(self, atom: str) -> bool:
        return self.set.retract(atom)

    def value(self, atom: str) -> bool | None:
        o = self.set.get(atom)
        return None if o is None else o.literal.positive
