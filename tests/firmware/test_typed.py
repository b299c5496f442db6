# cpython-only: reads the firmware's sources with ast, which MicroPython lacks
"""The firmware stays typed against its interfaces, and its typing never reaches the board.

mypy --strict checks ``firmware/`` (pyproject's ``files``) against ``firmware.hal.Hal``, the
``Board``, the stream protocols of ``firmware/net.py``; a ``# type: ignore`` is the way back to
untyped code, so their number in ``firmware/`` may only go down (``CEILING``: 251 before the
firmware was typed, 72 after a first pass, 19 once every module was typed: most of those left
reach MicroPython's own modules, which have no stubs), and no mypy override in pyproject.toml
may silence a firmware module (``ignore_errors``) instead. And since
MicroPython has no ``typing`` (nor ``collections.abc``) and ``dxboard flash`` ships only
``firmware/`` and ``protocol/``, every import of a typing module in ``firmware/`` must sit under
``if False:``, which MicroPython's compiler drops: a stray one would stop the board at boot.
Each check also runs on a small tree written into a temp dir, where it must find its fault.
"""

from __future__ import annotations

import ast
import re
import tomllib
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
CEILING = 17  # lower it whenever a change removes some; never raise it
IGNORE = re.compile(r"#\s*type:\s*ignore\b")
TYPING_ONLY = ("typing", "collections.abc", "typing_extensions")


def ignores(root: Path) -> list[str]:
    """Every ``# type: ignore`` under ``root/firmware`` as ``path:line``."""
    found = []
    for path in sorted((root / "firmware").rglob("*.py")):
        for n, line in enumerate(path.read_text(encoding="utf-8").splitlines(), 1):
            if IGNORE.search(line):
                found.append(f"{path.relative_to(root)}:{n}")
    return found


def _under_if_false(tree: ast.Module) -> set[int]:
    """The ids of the nodes inside an ``if False:`` body (not its ``else``)."""
    inside: set[int] = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.If) and isinstance(node.test, ast.Constant) \
                and node.test.value is False:
            for stmt in node.body:
                inside.update(id(sub) for sub in ast.walk(stmt))
    return inside


def runtime_typing_imports(root: Path) -> list[str]:
    """Imports of a typing module under ``root/firmware`` that would run on the board."""
    found = []
    for path in sorted((root / "firmware").rglob("*.py")):
        tree = ast.parse(path.read_text(encoding="utf-8"), filename=str(path))
        safe = _under_if_false(tree)
        for node in ast.walk(tree):
            if id(node) in safe:
                continue
            if isinstance(node, ast.Import):
                names = [a.name for a in node.names]
            elif isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
                names = [node.module]
            else:
                continue
            if any(n == t or n.startswith(t + ".") for n in names for t in TYPING_ONLY):
                found.append(f"{path.relative_to(root)}:{node.lineno}")
    return found


def silenced(pyproject: str) -> list[str]:
    """The firmware modules a mypy override of ``pyproject`` (TOML text) leaves unchecked."""
    found = []
    for override in tomllib.loads(pyproject).get("tool", {}).get("mypy", {}).get("overrides", []):
        if not override.get("ignore_errors"):
            continue
        modules = override.get("module", [])
        for m in [modules] if isinstance(modules, str) else modules:
            if m == "firmware" or m.startswith("firmware."):
                found.append(m)
    return found


def _tree(base: Path, files: dict[str, str]) -> Path:
    for name, text in files.items():
        path = base / "firmware" / name
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(text, encoding="utf-8")
    return base


def test_the_firmware_has_no_more_type_ignores_than_the_ceiling() -> None:
    found = ignores(ROOT)
    assert len(found) <= CEILING, (
        f"{len(found)} '# type: ignore' in firmware/, at most {CEILING} wanted: type the new "
        f"code (string annotations, typing imports under 'if False:') instead: "
        + ", ".join(found))


def test_the_count_sees_every_spelling_of_an_ignore(tmp_path: Path) -> None:
    root = _tree(tmp_path, {
        "a.py": "x = f()  # type: ignore[attr-defined]\ny = 1\n",
        "hal/b.py": "z = g()  #type:ignore\nw = h()  # type: ignore  # reason\n",
    })
    assert ignores(root) == ["firmware/a.py:1", "firmware/hal/b.py:1", "firmware/hal/b.py:2"]


def test_no_typing_import_runs_on_the_board() -> None:
    assert runtime_typing_imports(ROOT) == [], \
        "a typing import outside 'if False:' (MicroPython has no typing): move it under one"


@pytest.mark.parametrize("text, found", [
    ("from typing import Any\n", ["firmware/m.py:1"]),
    ("import typing\n", ["firmware/m.py:1"]),
    ("def f() -> None:\n    from collections.abc import Callable\n", ["firmware/m.py:2"]),
    ("if False:\n    pass\nelse:\n    from typing import Protocol\n", ["firmware/m.py:4"]),
    ("try:\n    from typing import Any\nexcept ImportError:\n    pass\n", ["firmware/m.py:2"]),
    ("if False:\n    from typing import Any\n\n    class P(Any):\n        import typing\n", []),
])
def test_a_typing_import_outside_if_false_is_found(tmp_path: Path, text: str,
                                                    found: list[str]) -> None:
    assert runtime_typing_imports(_tree(tmp_path, {"m.py": text})) == found


def test_no_mypy_override_silences_the_firmware() -> None:
    assert silenced((ROOT / "pyproject.toml").read_text(encoding="utf-8")) == [], \
        "pyproject.toml: a mypy override with ignore_errors for firmware/: type the module instead"


def test_a_silencing_override_is_found() -> None:
    text = """
[[tool.mypy.overrides]]
module = ["pddl", "pddl.*"]
ignore_missing_imports = true

[[tool.mypy.overrides]]
module = ["firmware.hal.profet", "host.cli"]
ignore_errors = true

[[tool.mypy.overrides]]
module = "firmware.main"
ignore_errors = true

[[tool.mypy.overrides]]
module = ["firmware.net"]
ignore_errors = false
"""
    assert silenced(text) == ["firmware.hal.profet", "firmware.main"]
