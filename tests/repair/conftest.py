"""Shared fixtures: the tedusar robot's planner and small hand-built models."""

from __future__ import annotations

from pathlib import Path

import pytest

from host.repair.planner import RepairPlanner

ROOT = Path(__file__).resolve().parents[2]
TEDUSAR = ROOT / "models" / "tedusar"


@pytest.fixture(scope="session")
def tedusar() -> RepairPlanner:
    return RepairPlanner.for_system(TEDUSAR)
