"""Consistency-based diagnosis (paper 000 §IV-C/D): which components are broken.

Pipeline of pure stages: a robot model (``load_system`` -> ``SystemModel``) or a tug model file
(``read_tug``) becomes a ``Theory`` (components, general clauses, priors; ``generate``); a
``Diagnoser`` holds the theory in an incremental SAT solver, takes observations (``S ⊕ o``,
with expiry, and windows held back while their inputs settle: ``lags``) and returns a
``DiagnosisResult``: the subset-minimal diagnoses most probable first (``max_count`` keeps the
most probable), and whether a bound cut the list. The stable public API is re-exported here.
"""

from host.diagnosis.diagnoser import Diagnoser, UnknownLiteral
from host.diagnosis.files import load_theory, read_observations
from host.diagnosis.generate import generate
from host.diagnosis.lags import observation_lags
from host.diagnosis.logic import Clause, Literal, Theory, ab, format_clauses, parse_literal
from host.diagnosis.model import (
    Component,
    Kind,
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

__all__ = [
    "ALGORITHMS",
    "Bound",
    "Clause",
    "Component",
    "Diagnoser",
    "Diagnosis",
    "DiagnosisResult",
    "Kind",
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
