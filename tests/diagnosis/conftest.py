"""Shared helpers for the diagnosis tests: the tedusar model and observation files."""

from __future__ import annotations

from pathlib import Path

import pytest

from host.diagnosis import Diagnoser, Theory, generate, load_system
from host.diagnosis.files import read_observations

ROOT = Path(__file__).resolve().parents[2]
TEDUSAR = ROOT / "models" / "tedusar"
SCENARIOS = TEDUSAR / "scenarios"


@pytest.fixture(scope="session")
def tedusar() -> Theory:
    return generate(load_system(TEDUSAR))


def diagnoser_for(theory: Theory, scenario: str, algorithm: str = "cardinality") -> Diagnoser:
    d = Diagnoser(theory, algorithm=algorithm)
    for obs in read_observations(SCENARIOS / f"{scenario}.obs", theory):
        d.observe(obs)
    return d
