"""Consistency-based diagnosis (paper 000 §IV-C/D): which components are broken.

Pipeline of pure stages: a robot model (``load_system`` -> ``SystemModel``) or a tug model file
(``read_tug``) becomes a ``Theory`` (components, general clauses, priors; ``generate``); a
``Diagnoser`` holds the theory in an incremental SAT solver, takes observations (``S ⊕ o``,
with expiry, and windows held back while their inputs settle: ``lags``) and returns a
``DiagnosisResult``: the subset-minimal diagnoses most probable first (``max_count`` keeps the
most probable), and whether a bound cut the list. The stable public API is re-exported here,
each name imported from its module on first use.
"""

from __future__ import annotations

import importlib
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:  # the names, for type checkers; at run time __getattr__ loads them
    from host.diagnosis.diagnoser import Diagnoser, UnknownLiteral
    from host.diagnosis.files import load_theory, read_observations
    from host.diagnosis.generation import generate
    from host.diagnosis.lags import observation_lags
    from host.diagnosis.logic import Clause, Literal, Theory, ab, format_clauses, parse_literal
    from host.diagnosis.model import (
        Component,
        ComponentKind,
        ModelError,
        Problem,
        SystemModel,
        check_system,
        load_system,
    )
    from host.diagnosis.observations import Observation, ObservationSet
    from host.diagnosis.result import Bound, Diagnosis, DiagnosisResult
    from host.diagnosis.search import ALGORITHMS
    from host.diagnosis.tug import dump_tug, read_tug, write_tug

_WHERE = {  # name -> the module defining it, imported on first use
    "ALGORITHMS": "host.diagnosis.search",
    "Bound": "host.diagnosis.result",
    "Clause": "host.diagnosis.logic",
    "Component": "host.diagnosis.model",
    "Diagnoser": "host.diagnosis.diagnoser",
    "Diagnosis": "host.diagnosis.result",
    "DiagnosisResult": "host.diagnosis.result",
    "ComponentKind": "host.diagnosis.model",
    "Literal": "host.diagnosis.logic",
    "ModelError": "host.diagnosis.model",
    "Observation": "host.diagnosis.observations",
    "ObservationSet": "host.diagnosis.observations",
    "Problem": "host.diagnosis.model",
    "SystemModel": "host.diagnosis.model",
    "Theory": "host.diagnosis.logic",
    "UnknownLiteral": "host.diagnosis.diagnoser",
    "ab": "host.diagnosis.logic",
    "check_system": "host.diagnosis.model",
    "dump_tug": "host.diagnosis.tug",
    "format_clauses": "host.diagnosis.logic",
    "generate": "host.diagnosis.generation",
    "load_system": "host.diagnosis.model",
    "load_theory": "host.diagnosis.files",
    "observation_lags": "host.diagnosis.lags",
    "parse_literal": "host.diagnosis.logic",
    "read_observations": "host.diagnosis.files",
    "read_tug": "host.diagnosis.tug",
    "write_tug": "host.diagnosis.tug",
}

__all__ = [
    "ALGORITHMS",
    "Bound",
    "Clause",
    "Component",
    "ComponentKind",
    "Diagnoser",
    "Diagnosis",
    "DiagnosisResult",
    "Literal",
    "ModelError",
    "Observation",
    "ObservationSet",
    "Problem",
    "SystemModel",
    "Theory",
    "UnknownLiteral",
    "ab",
    "check_system",
    "dump_tug",
    "format_clauses",
    "generate",
    "load_system",
    "load_theory",
    "observation_lags",
    "parse_literal",
    "read_observations",
    "read_tug",
    "write_tug",
]


def __getattr__(name: str) -> Any:
    """Import the module defining ``name`` on first use (PEP 562): ``dxboard diagnose`` on a tug
    model file then never loads the robot model's modules."""
    module = _WHERE.get(name)
    if module is None:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    value = getattr(importlib.import_module(module), name)
    globals()[name] = value
    return value
