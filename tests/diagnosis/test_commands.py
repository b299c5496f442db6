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


def test_diagnose_json_lists_what_is_bad(capsys: pytest.CaptureFixture[str]) -> None:
    obs = SCENARIOS / "device-shut-down.obs"
    assert cli.main(["diagnose", str(TEDUSAR), "--obs", str(obs), "--json"]) == 0
    data = json.loads(capsys.readouterr().out)
    assert data["complete"] is True and data["order"] == "probability"
    assert [d["bad"] for d in data["diagnoses"]] == [["jaguar"]]
    assert "good" not in data["diagnoses"][0]
    assert cli.main(["diagnose", str(TEDUSAR), "--obs", str(obs), "--json", "--good"]) == 0
    data = json.loads(capsys.readouterr().out)
    assert "jaguar_node" in data["diagnoses"][0]["good"]
    assert len(data["diagnoses"][0]["good"]) == 16  # 14 of the paper's model, and the camera


def test_diagnose_freezes_the_collector_only_while_it_runs(
        monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]) -> None:
    """The command hides the loaded model from the collector during the search
    (``gc.freeze``) and gives everything back at the end, on success and on error."""
    import gc

    from host.diagnosis import diagnoser

    seen: list[int] = []
    real = diagnoser.Diagnoser.diagnose

    def spy(self: diagnoser.Diagnoser, *a: object, **kw: object) -> object:
        seen.append(gc.get_freeze_count())
        return real(self, *a, **kw)  # type: ignore[arg-type]

    monkeypatch.setattr(diagnoser.Diagnoser, "diagnose", spy)
    obs = SCENARIOS / "device-shut-down.obs"
    assert gc.get_freeze_count() == 0
    assert cli.main(["diagnose", str(TEDUSAR), "--obs", str(obs), "--json"]) == 0
    assert seen and seen[0] > 0 and gc.get_freeze_count() == 0
    bad = obs.parent.parent / "no-such.obs"
    assert cli.main(["diagnose", str(TEDUSAR), "--obs", str(bad)]) == 2  # one line, exit 2
    assert gc.get_freeze_count() == 0
    capsys.readouterr()


def test_diagnose_freezes_the_cached_model_before_the_collector_runs_again(
        tmp_path: Path, monkeypatch: pytest.MonkeyPatch,
        capsys: pytest.CaptureFixture[str]) -> None:
    """A model read back from the cache is frozen before any collection: unpickling it does
    not set off a walk of every object it made (c7552: 4-12 ms a run)."""
    import gc

    from host.diagnosis import cache

    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "cache"))
    model = tmp_path / "tedusar.yaml"
    write_tug(generate(load_system(TEDUSAR)), model)
    obs = SCENARIOS / "device-shut-down.obs"
    args = ["diagnose", str(model), "--obs", str(obs), "--json"]
    assert cli.main(args) == 0  # fills the cache
    read: list[bool] = []
    real = cache.read_entry

    def spy(entry: Path, key: object) -> object | None:
        value = real(entry, key)
        read.append(value is not None)
        return value

    collections: list[tuple[bool, int]] = []  # (the entry read yet, objects frozen)

    def watch(phase: str, info: dict[str, int]) -> None:
        if phase == "start":
            collections.append((any(read), gc.get_freeze_count()))

    monkeypatch.setattr(cache, "read_entry", spy)
    threshold = gc.get_threshold()
    gc.set_threshold(10)  # a collection soon after any allocations, as a big model's
    gc.callbacks.append(watch)
    try:
        assert cli.main(args) == 0
    finally:
        gc.callbacks.remove(watch)
        gc.set_threshold(*threshold)
    assert read == [True]  # the model came from the cache
    after = [frozen for was_read, frozen in collections if was_read]
    assert after, "the search collected nothing: the test sees nothing"
    assert min(after) > 0, collections
    assert gc.get_freeze_count() == 0
    capsys.readouterr()


def test_no_consistent_diagnosis_says_so_and_exits_1(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    obs = tmp_path / "x.obs"  # a value cannot rise and fall at once, whatever is broken
    obs.write_text("~on(jaguar)\ninc(odom_yaw_rate)\ndec(odom_yaw_rate)\n")
    assert cli.main(["diagnose", str(TEDUSAR), "--obs", str(obs)]) == 1
    out = capsys.readouterr().out
    assert "no consistent diagnosis" in out and "bad:" not in out
    assert cli.main(["diagnose", str(TEDUSAR), "--obs", str(obs), "--json"]) == 1
    data = json.loads(capsys.readouterr().out)
    assert data["explainable"] is False and data["diagnoses"] == []




@pytest.mark.parametrize("flag", [["--time-budget", "-1"], ["--time-budget", "nan"],
                                  ["--max-count", "0"], ["--max-card", "-2"]])
def test_bad_bounds_are_refused(flag: list[str], capsys: pytest.CaptureFixture[str]) -> None:
    obs = SCENARIOS / "device-shut-down.obs"
    with pytest.raises(SystemExit) as info:
        cli.main(["diagnose", str(TEDUSAR), "--obs", str(obs), *flag])
    assert info.value.code == 2
    assert flag[0] in capsys.readouterr().err


def test_help_states_the_order_and_every_algorithm(capsys: pytest.CaptureFixture[str]) -> None:
    from host.commands import diagnose
    from host.diagnosis import ALGORITHMS
    from host.diagnosis.search import DEFAULT_ALGORITHM

    assert set(diagnose.ALGORITHMS) == set(ALGORITHMS)
    assert diagnose.DEFAULT_ALGORITHM == DEFAULT_ALGORITHM
    with pytest.raises(SystemExit):
        cli.main(["diagnose", "--help"])
    out = " ".join(capsys.readouterr().out.split())
    assert "most probable first" in out and "(default: auto)" in out
    for name in ALGORITHMS:
        assert f"{name}:" in out


def test_minimal_cardinality_only(capsys: pytest.CaptureFixture[str]) -> None:
    obs = SCENARIOS / "power-up.obs"
    assert cli.main(["diagnose", str(TEDUSAR), "--obs", str(obs), "--min-card-only",
                     "--json"]) == 0
    data = json.loads(capsys.readouterr().out)
    assert [len(d["bad"]) for d in data["diagnoses"]] == [11]


def test_diagnose_text_with_cut(capsys: pytest.CaptureFixture[str]) -> None:
    obs = SCENARIOS / "power-up.obs"
    assert cli.main(["diagnose", str(TEDUSAR), "--obs", str(obs), "--max-card", "3"]) == 1
    out = capsys.readouterr().out
    assert "no diagnosis found within the bounds" in out
    assert "incomplete: the max_card bound cut the list" in out


def test_diagnose_a_tug_file(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    model = tmp_path / "tedusar.yaml"
    write_tug(generate(load_system(TEDUSAR)), model)
    obs = SCENARIOS / "device-shut-down.obs"
    assert cli.main(["diagnose", str(model), "--obs", str(obs), "--json"]) == 0
    assert json.loads(capsys.readouterr().out)["diagnoses"][0]["bad"] == ["jaguar"]


@pytest.mark.parametrize(("text", "line", "needle"), [
    ("# header\nok(/scan)\nnot running(nobody)\n", 3, "running(nobody)"),  # unknown literal
    ("on(jaguar)\n~on(jaguar)\n", 2, "line 1"),  # contradictory lines: no 'bad: jaguar'
])
def test_bad_obs_file_is_one_line_and_exit_2(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], text: str, line: int, needle: str
) -> None:
    obs = tmp_path / "x.obs"
    obs.write_text(text)
    assert cli.main(["diagnose", str(TEDUSAR), "--obs", str(obs)]) == 2
    captured = capsys.readouterr()
    err = captured.err.strip()
    assert len(err.splitlines()) == 1 and "bad:" not in captured.out
    assert f"{obs}:{line}:" in err and needle in err and "Traceback" not in err


def test_bad_model_path_is_a_user_error(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    obs = tmp_path / "x.obs"
    obs.write_text("")
    assert cli.main(["diagnose", str(tmp_path / "none"), "--obs", str(obs)]) == 2
    assert "no such file" in capsys.readouterr().err


@pytest.mark.parametrize(("domain", "needle"), [
    ("(define (domain x) (:action a :parameters (?x) :effect (and (p ?x)))",
     "not a valid PDDL domain"),
    ((TEDUSAR / "repair.pddl").read_text().replace("(running ?n - node)", ""),
     "undeclared predicate(s) running"),
])
def test_model_check_checks_the_repair_domain(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], domain: str, needle: str
) -> None:
    (tmp_path / "system.yaml").write_text((TEDUSAR / "system.yaml").read_text())
    (tmp_path / "repair.pddl").write_text(domain)
    assert cli.main(["model", "check", str(tmp_path)]) == 1
    err = capsys.readouterr().err
    assert f"{tmp_path / 'repair.pddl'}" in err and needle in err
