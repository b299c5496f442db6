"""A lightweight robot for fleet tests and benchmarks: TEDUSAR's board and switchable devices only.

``lite_model(dest)`` copies ``models/tedusar`` into ``dest`` with its model cut down to the
switchable hardware (SH components on board channels) and the board observers: no nodes, no
topics, no processes, no ``robot.yaml`` (so no virtual devices), and the fast boot times of
``host.experiment.robot.fast_model``. A daemon on it is a board emulator plus one process, so
dozens fit on a small machine; faults are injected on its control port as on the full robot.
"""

from __future__ import annotations

import shutil
from pathlib import Path

import yaml

from host.experiment.robot import fast_model

ROOT = Path(__file__).resolve().parents[2]
TEDUSAR = ROOT / "models" / "tedusar"


def lite_model(dest: Path) -> Path:
    d = fast_model(TEDUSAR, dest)
    (d / "robot.yaml").unlink()
    shutil.rmtree(d / "scenarios")  # they name the nodes this model leaves out
    system = yaml.safe_load((d / "system.yaml").read_text())
    system["robot"] = "lite"
    system["components"] = {n: c for n, c in system["components"].items() if c["kind"] == "SH"}
    system["observers"] = {"hardware": system["observers"]["hardware"]}
    system.pop("processes", None)
    system.pop("values", None)
    system.pop("related", None)
    (d / "system.yaml").write_text(yaml.safe_dump(system))
    return d
