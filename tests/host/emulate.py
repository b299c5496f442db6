"""``dxboard emulate`` as a subprocess, as users start it: the launcher's ``RunningBoard``
(``host.launch.boards``: a ``host.launch.procs.Child`` that is up once it printed board,
control and a URL per front end asked for) on ``models/tedusar`` without its devices, with the
tests' key in its environment (``KEY_HEX``, ``ENV``: what the tests' own commands use too).
"""

from __future__ import annotations

import os
from pathlib import Path

from host.launch.boards import RunningBoard

ROOT = Path(__file__).resolve().parents[2]
KEY_HEX = "000102030405060708090a0b0c0d0e0f"
ENV = {**os.environ, "DXBOARD_KEY": KEY_HEX, "PYTHONPATH": str(ROOT)}


class Emulate(RunningBoard):
    """One ``dxboard emulate models/tedusar ...`` process and the URLs it printed."""

    def __init__(self, *options: str, env: dict[str, str] | None = None) -> None:
        super().__init__(ROOT / "models" / "tedusar", *options, key=bytes.fromhex(KEY_HEX),
                         robot=False, env={"PYTHONPATH": str(ROOT), **(env or {})})
