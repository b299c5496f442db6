"""Restart a node that was started elsewhere, through the actuator ``external:`` names for it.

The repair domain's ``restart_node(n)`` for a node of ``external:`` (``host.repair.external``):
``systemd: UNIT`` runs ``systemctl restart UNIT``, ``command: [argv...]`` runs the command,
``container: NAME`` runs ``docker restart NAME``; each must exit 0 within ``timeout_s``. The
node's own launcher (a unit, a launch file, a container) then starts it again: dxboard never
owns its process. What cannot be done is one line, never a traceback: a node without an
actuator is ``Refused`` ("not repairable here"; the planner does not plan it, see
``not_repairable``), a missing program (no ``systemctl``, no ``docker``), a refusal (a unit
the user may not restart: exit code 4) or a timeout is an ``ActuationError`` naming the node,
the command and the tail of its output. The executor verifies the effect by the node's
observations, as for every repair.
"""

from __future__ import annotations

import asyncio
import contextlib
import logging
import shlex
import tempfile
from collections.abc import Mapping

from host.repair.actuators import ActuationError, Refused
from host.repair.external import ExternalNode, not_repairable

log = logging.getLogger(__name__)

TIMEOUT_S = 60.0
PROGRAMS = {"systemd": ("systemctl", "restart"), "container": ("docker", "restart")}


def restart_argv(node: ExternalNode) -> tuple[str, ...]:
    """The command that restarts ``node`` (``Refused`` when it has no actuator)."""
    if node.kind is None:
        raise Refused(f"restart_node({node.node}): {not_repairable(node.node)}",
                      f"give {node.node} an actuator in external: (systemd, command, container)")
    if node.kind == "command":
        return node.target
    return (*PROGRAMS[node.kind], *node.target)


class RestartActuator:
    """``restart_node(n)`` for the executor's ``Actuators`` (``add("restart_node", ...)``)."""

    def __init__(self, external: Mapping[str, ExternalNode], timeout_s: float = TIMEOUT_S) -> None:
        self.external = dict(external)
        self.timeout_s = timeout_s

    async def restart_node(self, node: str) -> str:
        spec = self.external.get(node)
        if spec is None:
            raise Refused(f"restart_node({node}): {node} is not in external:",
                          "restart_node is for nodes started elsewhere")
        argv = restart_argv(spec)
        shown = shlex.join(argv)
        # its output into a file, not a pipe: a command that starts the node in the background
        # (as a launcher does) leaves the node holding a pipe open long after it exits
        with tempfile.TemporaryFile() as out:
            try:
                proc = await asyncio.create_subprocess_exec(
                    *argv, stdin=asyncio.subprocess.DEVNULL, stdout=out, stderr=out)
            except OSError as exc:
                raise ActuationError(f"restart_node({node}): cannot run {shown}: "
                                     f"{exc.strerror}", f"install {argv[0]}, or give {node} "
                                     "another actuator in external:") from None
            try:
                await asyncio.wait_for(proc.wait(), self.timeout_s)
            except TimeoutError:
                with contextlib.suppress(ProcessLookupError):
                    proc.kill()
                await proc.wait()
                raise ActuationError(f"restart_node({node}): {shown} did not finish within "
                                     f"{self.timeout_s:g} s", "check the command by hand"
                                     ) from None
            out.seek(0)
            tail = out.read().decode(errors="replace").strip().splitlines()[-1:]
        if proc.returncode != 0:
            said = f": {tail[0]}" if tail else ""
            raise ActuationError(f"restart_node({node}): {shown} refused (exit code "
                                 f"{proc.returncode}){said}",
                                 "may dxboard's user run it? (systemctl: a polkit rule or a "
                                 "user unit; docker: the docker group)")
        log.info("restarted %s: %s", node, shown)
        return f"{node} restarted by {shown}"
