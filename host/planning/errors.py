"""The repair package's errors, split by who must act (house style point 4).

``DomainError`` is a repair domain (PDDL) that cannot be loaded or uses a feature the grounder
does not support; ``ProblemError`` is a diagnosis or observation that does not fit the model
(an unknown component, a malformed literal); ``NoPlanError`` is a goal that no plan reaches,
with the reason (an unrepairable component, a protected one that would have to be switched
off). All three are ``UserError``s: a person fixes the file, the arguments or the robot. A
``PlanningLimitError`` is a search that ran out of its node budget; it is not the user's fault
but it is not a bug either, so it is a ``DxboardError``.
"""

from __future__ import annotations

from host.errors import DxboardError, UserError


class DomainError(UserError):
    """The repair domain cannot be used (parse error, unsupported feature)."""


class ProblemError(UserError):
    """The diagnosis, the observations or the model do not fit together."""


class NoPlanError(UserError):
    """No plan reaches the goal; ``unreachable`` names the goal literals that cannot be met."""

    def __init__(self, message: str, hint: str = "", unreachable: tuple[str, ...] = ()) -> None:
        super().__init__(message, hint)
        self.unreachable = unreachable


class PlanningLimitError(DxboardError):
    """The search expanded its whole node budget without finding a plan or proving none."""
