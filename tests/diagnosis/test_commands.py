"""``dxboard model`` and ``dxboard diagnose`` through the real CLI entry point."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from host import cli
from host.diagnosis import generate, load_system
from host.diagnosis.tug import write_tug
from tests.diagnosis.conftest import SCENARIOS, TEDUSAR


@pytest.fixture(autouse=True)
def only_diagnosis_commands(monkeypatch: pytest.MonkeyPatch) -> None:
    # other sub-commands are built by other issues; load only ours (as registered in cli.py)
    ours = {k: v for k, v in cli.COMMANDS.items() if k in ("model", "diagnose")}
    assert ours == {"model": "host.commands.model", "diagnose": "host.commands.diagnose"}
    monkeypatch.setattr(cli, "COMMANDS", ours)


def test_model_check_ok(capsys: pytest.CaptureFixture[str]) -> None:
    assert cli.main(["model", "check", str(TEDUSAR)]) == 0
    out = capsys.readouterr().out
    assert "ok (17 components" in out and "2 scenario file(s)" in out


def test_model_check_reports_problems(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    text = (TEDUSAR / "system.yaml").read_text().replace("channel: 3", "channel: 7")
    (tmp_path / "system.yaml").write_text(text)
    assert cli.main(["model", "check", str(tmp_path)]) == 1
    err = capsys.readouterr().err
    assert f"{tmp_path / 'system.yaml'}:" in err and "channel 7 used twice" in err


def test_model_check_rejects_unknown_literals_in_scenarios(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    (tmp_path / "system.yaml").write_text((TEDUSAR / "system.yaml").read_text())
    (tmp_path / "scenarios").mkdir()
    (tmp_path / "scenarios" / "x.obs").write_text("on(jaguar)\n~on(kinect)\n")
    assert cli.main(["model", "check", str(tmp_path)]) == 1
    err = capsys.readouterr().err
    assert f"{tmp_path / 'scenarios' / 'x.obs'}:2: on(kinect)" in err


def test_model_clauses(capsys: pytest.CaptureFixture[str]) -> None:
    assert cli.main(["model", "clauses", str(TEDUSAR)]) == 0
    out = capsys.readouterr().out
    assert "# 1 switchable hardware must be powered" in out
    assert "~AB(jaguar) -> on(jaguar)" in out


def test_diagnose_json(capsys: pytest.CaptureFixture[str]) -> None:
    obs = SCENARIOS / "device-shut-down.obs"
    assert cli.main(["diagnose", str(TEDUSAR), "--obs", str(obs), "--json"]) == 0
    data = json.loads(capsys.readouterr().out)
    assert data["complete"] is True
    assert [d["bad"] for d in data["diagnoses"]] == [["jaguar"]]
    assert "jaguar_node" in data["diagnoses"][0]["good"]
    assert len(data["diagnoses"][0]["good"]) == 16  # 14 of the paper's model, and the camera


def test_diagnose_text_with_cut(capsys: pytest.CaptureFixture[str]) -> None:
    obs = SCENARIOS / "power-up.obs"
    assert cli.main(["diagnose", str(TEDUSAR), "--obs", str(obs), "--max-card", "3"]) == 0
    out = capsys.readouterr().out
    assert "incomplete: the max_card bound cut the list" in out


def test_diagnose_a_tug_file(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    model = tmp_path / "tedusar.yaml"
    write_tug(generate(load_system(TEDUSAR)), model)
    obs = SCENARIOS / "device-shut-down.obs"
    assert cli.main(["diagnose", str(model), "--obs", str(obs), "--json"]) == 0
    assert json.loads(capsys.readouterr().out)["diagnoses"][0]["bad"] == ["jaguar"]


def test_unknown_literal_is_one_line_and_exit_2(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    obs = tmp_path / "x.obs"
    obs.write_text("# header\nok(/scan)\nnot running(nobody)\n")
    assert cli.main(["diagnose", str(TEDUSAR), "--obs", str(obs)]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1
    assert f"{obs}:3:" in err and "running(nobody)" in err and "Traceback" not in err


def test_bad_model_path_is_a_user_error(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    obs = tmp_path / "x.obs"
    obs.write_text("")
    assert cli.main(["diagnose", str(tmp_path / "none"), "--obs", str(obs)]) == 2
    assert "no such file" in capsys.readouterr().err
