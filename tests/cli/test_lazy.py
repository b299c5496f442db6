"""The command registry is lazy: a command loads its own module only, ``--help`` lists all.

Each check runs the real entry point in a process of its own (a fresh interpreter, so that
``sys.modules`` shows what one command really imports).
"""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest

from host import cli
from tests.diagnosis.test_tug import ORIGINAL

ROOT = Path(__file__).resolve().parents[2]
# the entry point with COMMANDS as given; prints, on stderr's last line, what was imported
_MAIN = """\
import json, sys
import host.cli as c
extra = json.loads(sys.argv[1])
c.COMMANDS.update(extra)
try:
    code = c.main(sys.argv[2:])
finally:
    sys.stdout.flush()
    print(json.dumps(sorted(sys.modules)), file=sys.stderr)
sys.exit(code)
"""


def dxboard(*args: str, extra: dict[str, str] | None = None) -> tuple[int, str, str, set[str]]:
    """Exit code, stdout, stderr (less the module list) and the modules the process imported."""
    proc = subprocess.run([sys.executable, "-c", _MAIN, json.dumps(extra or {}), *args],
                          capture_output=True, text=True, cwd=ROOT, timeout=300, check=False)
    *err, modules = proc.stderr.rstrip("\n").split("\n")
    return proc.returncode, proc.stdout, "\n".join(err), set(json.loads(modules))


@pytest.fixture
def model(tmp_path: Path) -> tuple[Path, Path]:
    (tmp_path / "m.yaml").write_text(ORIGINAL)
    (tmp_path / "x.obs").write_text("on(hokuyo)\n!ok(/scan)\n")
    return tmp_path / "m.yaml", tmp_path / "x.obs"


def test_diagnose_imports_its_own_command_module_only(model: tuple[Path, Path]) -> None:
    code, out, err, modules = dxboard("diagnose", str(model[0]), "--obs", str(model[1]),
                                      "--json")
    assert code == 0, err
    assert {"hokuyo_node"} in [set(d["bad"]) for d in json.loads(out)["diagnoses"]]
    commands = {m for m in modules if m.startswith("host.commands.")}
    assert commands == {"host.commands.diagnose", "host.commands.model"}  # print_notes
    # nothing of the daemon, the web page, the robot's model or the event loop
    assert not modules & {"asyncio", "aiohttp", "host.events", "host.diagnosis.model",
                          "host.diagnosis.generation"}


def test_help_lists_every_command() -> None:
    code, out, err, modules = dxboard("--help")
    assert code == 0, err
    for name, module in cli.COMMANDS.items():
        assert f"    {name} " in out, name
        assert module in modules


@pytest.mark.parametrize("args", [["-h", "diagnose"], ["nonsense"], ["--verbose", "-h"]])
def test_anything_but_a_command_first_loads_them_all(args: list[str]) -> None:
    code, out, err, modules = dxboard(*args)
    assert set(cli.COMMANDS.values()) <= modules
    assert code == (0 if "-h" in args else 2)
    listing = out if code == 0 else err
    assert "diagnose" in listing and "journal" in listing


def test_verbose_before_the_command_keeps_it_lazy() -> None:
    code, out, err, modules = dxboard("-v", "diagnose", "--help")
    assert code == 0, err
    assert "--min-card-only" in out and "host.commands.run" not in modules


@pytest.mark.parametrize(("argv", "chosen"), [
    (["diagnose", "m.yaml"], "diagnose"),
    (["-v", "--verbose", "plan"], "plan"),
    (["--help"], None),
    (["-h", "diagnose"], None),
    (["--verb", "diagnose"], None),  # an abbreviation: argparse decides, with every command
    (["m.yaml"], None),
    ([], None),
])
def test_chosen_command(argv: list[str], chosen: str | None) -> None:
    assert cli.chosen_command(argv) == chosen


def test_a_command_that_cannot_be_imported_says_so_in_one_line() -> None:
    ghost = {"ghost": "host.commands.no_such_module"}
    code, out, err, _ = dxboard("ghost", "--json", extra=ghost)
    assert code == 2 and out == ""
    assert err.splitlines() == [
        "dxboard ghost: error: cannot load host.commands.no_such_module: No module named "
        "'host.commands.no_such_module' (install dxboard with its dependencies: make "
        ".venv/.installed)"]
    # the listing names it as unavailable and still lists every other command
    code, out, err, _ = dxboard("--help", extra=ghost)
    assert code == 0, err
    assert "ghost" in out and "unavailable: No module named" in out and "diagnose" in out
    # -v adds the traceback
    code, out, err, _ = dxboard("-v", "ghost", extra=ghost)
    assert code == 2 and "Traceback" in err and err.endswith("make .venv/.installed)")
