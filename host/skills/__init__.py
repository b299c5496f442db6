"""Layer 1 of the mission stack (paper 001 §III-A): the robot's skills, seen from the host.

``layer0`` folds the daemon's event stream into what the layers above need of layer 0 (which
components are diagnosed, repaired, quarantined or held, which topics are down) and answers
whether a skill's needs are available; ``client`` speaks to the world's skill servers
(``emulator.robot.world``); ``skill`` runs one goal as layer 1's decision making, monitor (progress,
timeout, resources) and diagnoser (a failure explained by layer 0's diagnosis or the world).
"""

from host.skills.client import GoalHandle, WorldClient
from host.skills.layer0 import Availability, AvailState, Layer0View
from host.skills.skill import Skill, SkillSpec

__all__ = [
           "AvailState",
           "Availability",
           "GoalHandle",
           "Layer0View",
           "Skill",
           "SkillSpec",
           "WorldClient",
]
