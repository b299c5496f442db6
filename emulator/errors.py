"""The emulator's exceptions: one family, split by who is at fault (as ``host.errors`` is).

``EmulatorError`` is the root. ``InputError``: something a person gave is wrong and the
message says where and how to fix it — the emulator model (``EmulatorModelError``; the virtual
robot's devices and nodes: ``RobotModelError``), a fault or its parameters (``FaultError``), a
scenario file (``ScenarioError``), a start option (``StartError``), what a node was started
with (``NodeError``). ``PartFailure``: a part of the emulator itself failed — the micropython
process or its link (``MicroError``). The command line turns an ``InputError`` into one line
and exit code 2; a ``PartFailure`` says which part failed. The emulator imports nothing of
the host, so these are its own classes, not the host's.
"""

from __future__ import annotations


class EmulatorError(Exception):
    """Base of every error the emulator raises on purpose."""


class InputError(EmulatorError, ValueError):
    """A file, option or request a person gave is wrong; the message says what to fix."""


class PartFailure(EmulatorError, RuntimeError):
    """A part of the emulator (a child process, a link) failed."""
