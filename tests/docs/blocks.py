"""The runnable blocks of the docs: what ``test_commands.py`` extracts and runs.

A runnable block is a fenced ``console`` block; each line that starts with ``$ `` is a command,
the lines after it (up to the next command) are output the command must print, ``...``
standing for anything (a port, a time, a run id); a shown line ``[exit N]`` says the command
exits N (default 0: the troubleshooting page shows real error lines this way). A ``console``
block titled ``runs until Ctrl-C`` holds one long-running command: it is started, its shown
lines awaited, then stopped with SIGINT. Other fences (``sh``, ``text``) are shown, not run; a
page names the tests that cover what it shows that way.
"""

from __future__ import annotations

import importlib.util
import re
import sys
from dataclasses import dataclass, field
from pathlib import Path
from types import ModuleType

ROOT = Path(__file__).resolve().parents[2]
DOCS = ROOT / "docs"
_FENCE = re.compile(r"^(`{3,})console(?P<attrs>[^\n]*)$")
LONG_RUNNING = "runs until Ctrl-C"


_EXIT = re.compile(r"^\[exit (\d+)\]$")


@dataclass
class Command:
    line: str
    shown: list[str] = field(default_factory=list)
    exit_code: int = 0

    def patterns(self) -> list[re.Pattern[str]]:
        """Each shown line as a pattern of a whole output line (``...``: anything)."""
        return [re.compile(".*".join(re.escape(part) for part in s.split("...")))
                for s in self.shown]


@dataclass
class Block:
    page: Path
    lineno: int
    long_running: bool
    commands: list[Command]

    @property
    def name(self) -> str:
        return f"{self.page.relative_to(DOCS)}:{self.lineno}"


def blocks(page: Path) -> list[Block]:
    """The runnable blocks of ``page`` in order."""
    lines = page.read_text(encoding="utf-8").splitlines()
    out: list[Block] = []
    i = 0
    while i < len(lines):
        m = _FENCE.match(lines[i].strip())
        if not m:
            i += 1
            continue
        fence, start = m.group(1), i + 1
        commands: list[Command] = []
        i += 1
        while i < len(lines) and lines[i].strip() != fence:
            text = lines[i].rstrip()
            if text.startswith("$ "):
                commands.append(Command(text[2:]))
            elif text and commands and (code := _EXIT.match(text.strip())):
                commands[-1].exit_code = int(code.group(1))
            elif text and commands:
                commands[-1].shown.append(text.strip())
            i += 1
        out.append(Block(page, start, LONG_RUNNING in m.group("attrs"), commands))
        i += 1
    return out


def pages() -> list[Path]:
    return sorted(DOCS.rglob("*.md"))


def unmatched(command: Command, output: str) -> list[str]:
    """The shown lines of ``command`` that no line of ``output`` is."""
    got = [line.strip() for line in output.splitlines()]
    return [shown for shown, pat in zip(command.shown, command.patterns(), strict=True)
            if not any(pat.fullmatch(line) for line in got)]


def gen_docs() -> ModuleType:
    """``scripts/gen_docs.py``, the maker of the site's generated pages (the mkdocs hook)."""
    if "gen_docs" not in sys.modules:
        spec = importlib.util.spec_from_file_location("gen_docs", ROOT / "scripts" / "gen_docs.py")
        assert spec is not None and spec.loader is not None
        module = importlib.util.module_from_spec(spec)
        sys.modules["gen_docs"] = module
        spec.loader.exec_module(module)
    return sys.modules["gen_docs"]
