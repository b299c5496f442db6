"""Files the ``model`` and ``diagnose`` commands read: a model of either format, observations.

``load_theory(path)`` takes a robot directory (or its ``system.yaml``), validated and turned
into clauses, or a tug model file. ``read_observations(path, theory)`` reads one literal a line
(``ok(/scan)``, ``~on(jaguar)``, ``not on(jaguar)``; ``#`` starts a comment) and rejects a
literal the model does not mention, naming the file, line and fix.
"""

from __future__ import annotations

from pathlib import Path

from host.diagnosis.generate import generate
from host.diagnosis.logic import Theory, parse_literal
from host.diagnosis.model import SYSTEM_FILE, load_system
from host.diagnosis.observations import Observation
from host.diagnosis.tug import is_tug_file, read_tug
from host.errors import UserError


def load_theory(path: str | Path) -> Theory:
    p = Path(path)
    if p.is_dir() or p.name == SYSTEM_FILE:
        return generate(load_system(p))
    if is_tug_file(p):
        return read_tug(p)
    if not p.exists():
        raise UserError(f"{p}: no such file or directory",
                        "give a robot directory (with system.yaml) or a tug model file")
    raise UserError(f"{p}: neither a robot directory nor a tug model file",
                    "give a directory holding system.yaml or a YAML file with props and rules")


def read_observations(path: str | Path, theory: Theory, time: float = 0.0) -> list[Observation]:
    file = Path(path)
    try:
        text = file.read_text(encoding="utf-8")
    except OSError as exc:
        raise UserError(f"{file}: cannot read: {exc.strerror}",
                        "give a file with one literal a line") from exc
    known = theory.observable_atoms()
    out: list[Observation] = []
    for number, raw in enumerate(text.splitlines(), start=1):
        line = raw.split("#", 1)[0].strip()
        if not line:
            continue
        try:
            lit = parse_literal(line)
        except ValueError as exc:
            raise UserError(f"{file}:{number}: {exc}",
                            "write one literal a line, e.g. ok(/scan) or ~on(jaguar)") from exc
        if lit.atom not in known:
            close = sorted(a for a in known if a.split("(")[0] == lit.atom.split("(")[0])[:5]
            hint = f"the model knows e.g. {', '.join(close)}" if close else "check the name"
            raise UserError(f"{file}:{number}: {lit.atom} is mentioned by no clause of the model",
                            hint)
        out.append(Observation(lit, time, source=str(file)))
    return out
