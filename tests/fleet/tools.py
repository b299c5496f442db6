"""The real Prometheus tools for the fleet tests: ``promtool``, ``prometheus``, ``alertmanager``.

Debian's packages (prometheus 2.42 with promtool, prometheus-alertmanager 0.25), installed by
``scripts/ensure-prometheus`` (the Makefile's pytest target) when missing. ``tool(name)`` is the
path of one, or fails the test saying how to install it; ``promtool(*args)`` runs it and
returns its exit code and output; ``samples(text)`` reads an exposition into
``{'name{labels}': value}`` with a parser of its own (no code shared with prometheus-client).
"""

from __future__ import annotations

import re
import subprocess

import pytest

from host.errors import UserError
from host.launch.prometheus import binary

SAMPLE = re.compile(r'^([a-zA-Z_:][a-zA-Z0-9_:]*)(\{.*\})? (\S+)$')


def tool(name: str) -> str:
    """The launcher's ``binary(name)``; a missing one fails the test saying how to install it."""
    try:
        return binary(name)
    except UserError as exc:
        pytest.fail(str(exc))  # "prometheus is not installed (run scripts/ensure-...)"


def promtool(*args: str, stdin: str | None = None, cwd: str | None = None) -> tuple[int, str]:
    out = subprocess.run([tool("promtool"), *args], input=stdin, capture_output=True,
                         text=True, timeout=120, cwd=cwd)
    return out.returncode, out.stdout + out.stderr


def samples(text: str) -> dict[str, float]:
    out: dict[str, float] = {}
    for line in text.splitlines():
        if not line or line.startswith("#"):
            continue
        m = SAMPLE.match(line)
        assert m, f"not a sample line: {line!r}"
        out[m.group(1) + (m.group(2) or "")] = float(m.group(3))
    return out
