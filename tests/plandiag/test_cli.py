"""``dxboard explain`` end to end: through ``host.cli.main``, and once as a real process."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest

import host.cli
from tests.plandiag.conftest import ARENA


@pytest.fixture(autouse=True)
def only_explain(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(host.cli, "COMMANDS", {"explain": "host.commands.explain"})


def test_m2_as_text(capsys: pytest.CaptureFixture[str]) -> None:
    assert host.cli.main(["explain", str(ARENA / "m2-door-closed.json"), str(ARENA)]) == 0
    out = capsys.readouterr().out
    assert "propagated: ~open(door1) observed pre step 13" in out
    assert "door-closes(door1) between steps 3 and 13" in out
    assert "class: exogenous event" in out


def test_m4_as_json_with_the_context_tree(capsys: pytest.CaptureFixture[str]) -> None:
    code = host.cli.main(["explain", str(ARENA / "m4-plan-error.json"), str(ARENA),
                          "--engine", "tree", "--json"])
    assert code == 0
    out = json.loads(capsys.readouterr().out)
    assert out["classes"] == ["plan error"] and out["histories"] == []
    assert out["plan_error"]["missing_conditions"][0]["condition"] == "(not (locked ?d))"
    assert out["engine"] == "tree" and out["explainable"] is False


def test_m3_by_probability_lists_the_action_fault_first(
        capsys: pytest.CaptureFixture[str]) -> None:
    code = host.cli.main(["explain", str(ARENA / "m3-marker-missing.json"), str(ARENA),
                          "--order", "probability", "--max-count", "3", "--json"])
    assert code == 0
    out = json.loads(capsys.readouterr().out)
    assert out["histories"][0]["faults"][0]["action"] == "mark-not-placed"
    assert len(out["histories"]) == 3 and out["cut_by"] == "max_count"
    assert out["complete"] is False


@pytest.mark.parametrize(("args", "message"), [
    (["--engine", "magic"], "unknown engine 'magic'"),
    (["--order", "size"], "unknown order 'size'"),
    (["--max-card", "-1"], "--max-card -1 is negative"),
    (["--time-budget", "0"], "--time-budget 0.0 is not positive"),
])
def test_bad_arguments_are_one_line_and_exit_2(
        capsys: pytest.CaptureFixture[str], args: list[str], message: str) -> None:
    code = host.cli.main(["explain", str(ARENA / "m2-door-closed.json"), str(ARENA), *args])
    err = capsys.readouterr().err
    assert code == 2 and message in err and len(err.strip().splitlines()) == 1


def test_a_bad_history_file_is_one_line_and_exit_2(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    bad = tmp_path / "h.json"
    data = json.loads((ARENA / "m2-door-closed.json").read_text())
    data["steps"][1]["action"] = "teleport"
    bad.write_text(json.dumps(data))
    assert host.cli.main(["explain", str(bad), str(ARENA)]) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith("dxboard explain: error: steps[1]: unknown action 'teleport'")
    assert "Traceback" not in err and len(err.splitlines()) == 1


def test_the_command_runs_as_a_process() -> None:
    proc = subprocess.run(
        [sys.executable, "-m", "host.cli", "explain", str(ARENA / "m3-marker-missing.json"),
         str(ARENA)], capture_output=True, text=True, timeout=120, check=False)
    assert proc.returncode == 0, proc.stderr
    assert "1. p=0.781  action fault: mark-not-placed(tedusar,v1,room1) at step 5" in proc.stdout
    help_text = subprocess.run(
        [sys.executable, "-m", "host.cli", "explain", "--help"], capture_output=True,
        text=True, timeout=120, check=True).stdout
    assert "; @mode ACTION prior=P" in help_text and "--engine" in help_text
