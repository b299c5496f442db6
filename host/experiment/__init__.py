"""Paper 000's two experiments (§VI) and the missions' (MISSIONS.md) on the virtual robot, as
``dxboard experiment``.

- ``session``: the robot and the daemon, in this process (``RobotSession``): the emulated board
  with its devices as a child process (``EmulatedBoard``, as ``dxboard run --emulate`` does),
  the ``Daemon`` on free ports, its journal; fault injection and an operator's switch.
- ``measure``: what the journal says happened — the diagnosis the first plan was made on, the
  plans, each action's start and end, when the robot became and stayed all-normal.
- ``experiments``: power-up (§VI-A; parallel and one step at a time) and device shut-down
  (§VI-B), each returning plain results.
- ``render``: the human-readable report and the ``--json`` form.
- ``robot``: a copy of a robot model with short device boot times (``--fast``).
- ``mission``: a mission run on the virtual robot (``dxboard mission``) and M1 (mission-fault).
- ``plandiag``: M2-M4, plan-execution diagnosis of events injected through the arena.
"""

from host.experiment.experiments import device_shutdown, power_up
from host.experiment.measure import ActionTime, RunResult
from host.experiment.session import RobotSession

__all__ = ["ActionTime", "RobotSession", "RunResult", "device_shutdown", "power_up"]
