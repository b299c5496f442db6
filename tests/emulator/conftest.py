"""Fixtures: the TEDUSAR emulator on a simulated clock, provisioned with its board config."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from emulator import model
from emulator.sim import Emulator

TEDUSAR = Path(__file__).resolve().parents[2] / "models" / "tedusar"


def tedusar(**kw: object) -> Emulator:
    cfg = json.loads((TEDUSAR / "board.json").read_text())
    return Emulator(model.load(TEDUSAR), board_config=cfg, **kw)  # type: ignore[arg-type]


@pytest.fixture
def emu() -> Emulator:
    """TEDUSAR booted, pc on; then every other device switched on and settled."""
    e = tedusar()
    e.advance(500)
    for ch in (0, 1, 3, 4, 5, 6, 7):
        assert e.board.switch(ch, True)[0] == 0
    e.advance(2000)
    return e
