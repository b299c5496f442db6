"""Shared fixtures of the plan-diagnosis tests: the test arena's model and its histories."""

from __future__ import annotations

from pathlib import Path

import pytest

from host.plandiag.history import History, load_history
from host.plandiag.model import PlanModel, load_model

ARENA = Path(__file__).parent / "arena"


@pytest.fixture(scope="session")
def arena() -> PlanModel:
    return load_model(ARENA)


def arena_history(name: str) -> History:
    """One of the arena's recorded histories (``m2-door-closed`` ...)."""
    return load_history(ARENA / f"{name}.json")
