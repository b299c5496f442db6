"""``dxboard plan`` end to end through ``host.cli.main``."""

from __future__ import annotations

import json
from pathlib import Path

import pytest
from pddl.parser.problem import ProblemParser

import host.cli
from tests.diagnosis.originals import DOMAIN, JAGUAR_2012, PROBLEM

from .conftest import TEDUSAR


@pytest.fixture(autouse=True)
def only_plan(monkeypatch: pytest.MonkeyPatch) -> None:
    # other sub-commands are built by other people in parallel; test ours on its own
    monkeypatch.setattr(host.cli, "COMMANDS", {"plan": "host.commands.plan"})


def test_json_plan_for_the_jaguar_scenario(capsys: pytest.CaptureFixture[str]) -> None:
    assert host.cli.main(["plan", str(TEDUSAR), "--bad", "jaguar", "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert [{"action": s["action"], "args": s["args"]} for s in out["plan"]] == [
        {"action": "power_up", "args": ["jaguar"]},
        {"action": "stop_node", "args": ["jaguar_node"]},
        {"action": "start_node", "args": ["jaguar_node"]},
    ]
    assert [s["after"] for s in out["plan"]] == [[], [0], [1]]
    assert out["strategy"] == "single"


def test_observations_file_and_problem_output(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    obs = tmp_path / "obs.txt"
    obs.write_text("# the board says hokuyo is powered\non(hokuyo)\nok(/scan)\n")
    problem = tmp_path / "problem.pddl"
    code = host.cli.main(["plan", str(TEDUSAR), "--bad", "hokuyo", "--obs", str(obs),
                          "--write-problem", str(problem)])
    assert code == 0
    text = capsys.readouterr().out
    assert "power_cycle(hokuyo)" in text and "start_node(hokuyo_node)" in text
    parsed = ProblemParser()(problem.read_text())
    assert "(on hokuyo)" in {str(f) for f in parsed.init}


def test_diagnoses_file_from_dxboard_diagnose(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    diag = tmp_path / "d.json"
    diag.write_text(json.dumps({"diagnoses": [
        {"bad": ["hokuyo"], "good": [], "probability": 0.9},
        {"bad": ["jaguar"], "good": [], "probability": 0.1}]}))
    assert host.cli.main(["plan", str(TEDUSAR), "--diagnoses", str(diag), "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["repairs"] == ["hokuyo"] and out["strategy"] == "most-probable"


@pytest.mark.parametrize(
    ("argv", "needle"),
    [
        (["--bad", "nosuch"], "nosuch"),
        (["--bad", "imu"], "imu stays abnormal"),
        (["--bad", "jaguar", "--planner", "magic"], "magic"),
        (["--bad", "jaguar", "--obs", "/nonexistent/obs.txt"], "/nonexistent/obs.txt"),
        ([], "--bad"),
    ],
)
def test_user_errors_are_one_line_with_exit_2(
    argv: list[str], needle: str, capsys: pytest.CaptureFixture[str]
) -> None:
    assert host.cli.main(["plan", str(TEDUSAR), *argv]) == 2
    err = capsys.readouterr().err
    assert needle in err and err.count("\n") == 1 and "Traceback" not in err




@pytest.mark.parametrize(("text", "needle"), [
    ("on(jaguar)\non(jaguar\n", "on(jaguar"),  # malformed
    ("on(jaguar)\non(kinect)\n", "on(kinect)"),  # a literal the model does not know
])
def test_bad_observation_line_names_file_and_line(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], text: str, needle: str
) -> None:
    obs = tmp_path / "obs.txt"
    obs.write_text(text)
    assert host.cli.main(["plan", str(TEDUSAR), "--bad", "jaguar", "--obs", str(obs)]) == 2
    err = capsys.readouterr().err
    assert f"{obs}:2:" in err and needle in err and err.count("\n") == 1


def test_a_tug_model_with_the_original_domain(capsys: pytest.CaptureFixture[str],
                                              tmp_path: Path) -> None:
    obs = tmp_path / "obs.txt"
    obs.write_text("on(hokuyo)\nnot_ok(scan)\n")  # the model's own negation prefix
    assert host.cli.main(["plan", str(JAGUAR_2012), "--domain", str(DOMAIN), "--bad", "hokuyo",
                          "--obs", str(obs), "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert [(s["action"], s["args"]) for s in out["plan"]] == [
        ("shutdown", ["hokuyo"]), ("power_up", ["hokuyo"])]


def test_a_tug_model_needs_a_domain(capsys: pytest.CaptureFixture[str]) -> None:
    assert host.cli.main(["plan", str(JAGUAR_2012), "--bad", "hokuyo"]) == 2
    assert "--domain" in capsys.readouterr().err


def resolved(side: int) -> str:
    """One side of the merge conflict in the original's problem file (the sample as it is
    holds both sides and the markers)."""
    lines = PROBLEM.read_text().splitlines()
    mid = next(i for i, line in enumerate(lines) if line.startswith("======="))
    return "\n".join(lines[1:mid] if side == 0 else lines[mid + 1:-1]) + "\n"


@pytest.mark.parametrize(("side", "expected"), [
    (0, [["stop_node", "robot_pose_ekf"], ["start_node", "robot_pose_ekf"]]),
    (1, [["start_node", "sicklms"]]),
])
def test_the_originals_problem_files_plan(
    side: int, expected: list[list[str]], tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    problem = tmp_path / "repair_problem.pddl"
    problem.write_text(resolved(side))
    assert host.cli.main(["plan", "--problem", str(problem), "--domain", str(DOMAIN),
                          "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert [[s["action"], *s["args"]] for s in out["plan"]] == expected


def test_a_problem_file_with_a_merge_conflict_is_refused(
    capsys: pytest.CaptureFixture[str]
) -> None:
    assert host.cli.main(["plan", "--problem", str(PROBLEM), "--domain", str(DOMAIN)]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and f"{PROBLEM}:1: an unresolved git merge conflict" in err


def test_a_problem_for_another_domain_is_refused(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    problem = tmp_path / "p.pddl"
    problem.write_text(resolved(1).replace("(:domain repair_domain)", "(:domain light_domain)"))
    assert host.cli.main(["plan", "--problem", str(problem), "--domain", str(DOMAIN)]) == 2
    assert "light_domain" in capsys.readouterr().err
