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


@pytest.fixture(autouse=True)
def _own_cache_dir(tmp_path_factory: pytest.TempPathFactory,
                   monkeypatch: pytest.MonkeyPatch) -> Path:
    """``dxboard diagnose`` keeps parsed models in the user's cache directory: each test gets
    a fresh one (its processes inherit it), never the person's ~/.cache."""
    path = tmp_path_factory.mktemp("xdg-cache")
    monkeypatch.setenv("XDG_CACHE_HOME", str(path))
    return path
