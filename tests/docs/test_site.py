"""The docs site builds strictly with its pages made from the code, and a broken link fails the
build (so the strict build is a real check, not a formality).

``mkdocs build --strict`` (mkdocs-material) writes into ``tmp_path``, never into the checkout.
"""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
from pathlib import Path

from tests.docs.blocks import ROOT

ENV = {**os.environ, "PYTHONPATH": str(ROOT), "NO_MKDOCS_2_WARNING": "1"}


def build(project: Path, out: Path) -> subprocess.CompletedProcess[str]:
    return subprocess.run([sys.executable, "-m", "mkdocs", "build", "--strict", "-f",
                           str(project / "mkdocs.yml"), "-d", str(out)], cwd=project, env=ENV,
                          capture_output=True, text=True, timeout=600)


def test_the_site_builds_strictly(tmp_path: Path) -> None:
    done = build(ROOT, tmp_path / "site")
    assert done.returncode == 0, done.stderr[-4000:]
    assert "WARNING" not in done.stderr, done.stderr[-4000:]
    for page in ("index.html", "getting-started/index.html", "reference/commands/index.html",
                 "reference/system-yaml/index.html", "reference/protocol/index.html",
                 "architecture/index.html", "troubleshooting/index.html"):
        assert (tmp_path / "site" / page).is_file(), page
    # the protocol page holds the normative text itself, included from protocol/PROTOCOL.md
    protocol = (tmp_path / "site" / "reference/protocol/index.html").read_text()
    assert "The Modbus TCP register map" in protocol and "Golden vectors" in protocol


def test_a_broken_link_fails_the_build(tmp_path: Path) -> None:
    project = tmp_path / "project"
    project.mkdir()
    for name in ("docs", "protocol", "host", "scripts"):
        shutil.copytree(ROOT / name, project / name, ignore=shutil.ignore_patterns("__pycache__"))
    shutil.copy(ROOT / "mkdocs.yml", project / "mkdocs.yml")
    page = project / "docs" / "getting-started.md"
    page.write_text(page.read_text() + "\nSee [nothing](no-such-page.md).\n")
    done = build(project, tmp_path / "site")
    assert done.returncode != 0 and "no-such-page.md" in done.stderr, done.stderr[-4000:]


def test_the_generated_pages_are_built_from_the_code(tmp_path: Path) -> None:
    """commands, system.yaml, packages and errors are made as the site builds (the hook in
    mkdocs.yml): every command, every host package, a known error and a known key are there."""
    from host.cli import COMMANDS

    done = build(ROOT, tmp_path / "site")
    assert done.returncode == 0, done.stderr[-4000:]
    ref = tmp_path / "site" / "reference"
    commands = (ref / "commands" / "index.html").read_text()
    missing = [n for n in COMMANDS if f"<h2 id=\"dxboard-{n}\">dxboard {n}" not in commands]
    assert not missing, missing
    packages = (ref / "packages" / "index.html").read_text()
    for init in (ROOT / "host").glob("*/__init__.py"):
        assert f"host/{init.parent.name}/" in packages
    assert "own_time" in (ref / "system-yaml" / "index.html").read_text()
    assert "no daemon's operator socket here" in (ref / "errors" / "index.html").read_text()
