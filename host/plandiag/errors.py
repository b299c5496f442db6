"""The plan-diagnosis package's errors, split by who must act (house style point 4).

``PlanModelError`` is a mission domain or fault file (PDDL) that cannot be used: a syntax
error, a fault mode naming an action the domain lacks, a missing prior. ``HistoryError`` is an
executed history (JSON) that does not fit the domain: an unknown action or object, an
observation at a step that does not exist. Both are ``UserError``s that name the file and the
place and say what to change; the command line prints them as one line with exit code 2.
"""

from __future__ import annotations

from host.errors import UserError


class PlanModelError(UserError):
    """The mission domain or its fault modes and events cannot be used."""


class HistoryError(UserError):
    """The executed history does not fit the domain, or is not a history at all."""
