"""The original system's own model files (``../shared/data/tug-original``) load and diagnose.

Scenarios and expected diagnoses are written here by hand from the rules of each file.
"""

from __future__ import annotations

from pathlib import Path

import pytest

from host import cli
from host.diagnosis import Diagnoser, Theory, load_theory
from host.diagnosis.files import read_observations
from host.errors import UserError
from tests.diagnosis.originals import (
    BROKEN_YAML,
    FINAL,
    JAGUAR_2012,
    MODEL2,
    PIONEER,
    PROTOTYPE,
)


def diagnose(theory: Theory, tmp_path: Path, lines: str) -> list[frozenset[str]]:
    obs = tmp_path / "x.obs"
    obs.write_text(lines)
    with Diagnoser(theory) as d:
        for o in read_observations(obs, theory):
            d.observe(o)
        result = d.diagnose()
        assert result.explainable
        return sorted(result.bad_sets(), key=sorted)


def test_atoms_missing_from_props_are_accepted_and_said_once(tmp_path: Path) -> None:
    theory = load_theory(JAGUAR_2012)
    assert len(theory.notes) == 1
    assert "ok(cmd_vel)" in theory.notes[0] and str(JAGUAR_2012) in theory.notes[0]
    # the original's own negation prefix in the observation file; ok(cmd_vel) is an atom
    # props does not list, so (as in the original engine) not_ok(cmd_vel) is an atom of its
    # own that no rule reads: it implicates nobody (test_tug_negation.py)
    assert diagnose(theory, tmp_path, "on(jaguar)\nnot_ok(odom)\nnot_ok(cmd_vel)\n") == [
        frozenset({"jaguar_node"})]
    assert diagnose(theory, tmp_path, "not_on(hokuyo)\n") == [frozenset({"hokuyo"})]


def test_every_missing_atom_is_listed_in_the_one_note() -> None:
    theory = load_theory(MODEL2)
    assert len(theory.notes) == 1
    note = theory.notes[0]
    assert "2 atoms" in note and "ok(diagnostics)" in note and "ok(imu_data)" in note
    assert {"ok(diagnostics)", "ok(imu_data)"} <= theory.observable_atoms()


def test_the_prototype_format_with_mappings(tmp_path: Path) -> None:
    theory = load_theory(PROTOTYPE)
    assert set(theory.components) == {"USB", "Node1", "Node2"}
    # rule 4: a broken USB silences topic 2, which is ok: USB works, so Node1 is broken
    assert diagnose(theory, tmp_path, "not_ok(Topic1_Frequency)\nok(Topic2_Frequency)\n") == [
        frozenset({"Node1"})]
    assert diagnose(theory, tmp_path, "not_ok(Topic1_Frequency)\nnot_ok(Topic2_Frequency)\n") == [
        frozenset({"Node1", "Node2"}), frozenset({"USB"})]


def test_invalid_yaml_names_file_and_line(capsys: pytest.CaptureFixture[str]) -> None:
    with pytest.raises(UserError) as info:
        load_theory(BROKEN_YAML)
    assert f"{BROKEN_YAML}:2:" in str(info.value) and "YAML" in str(info.value)
    assert cli.main(["model", "clauses", str(BROKEN_YAML)]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and f"{BROKEN_YAML}:2:" in err


@pytest.mark.parametrize(("model", "obs", "expected"), [
    # pioneer: move_base gets tf and scan, yet its outputs stop
    (PIONEER, "running(move_base)\nok(tf)\nok(scan)\nnot_ok(cmd_vel)\n", [{"move_base"}]),
    # the laser stops: the driver or (through scan) nothing else, since amcl still works
    (PIONEER, "running(sicklms)\nnot_ok(scan)\nok(tf)\n", [{"sicklms"}]),
    # Final: p2os is not running
    (FINAL, "not_running(p2os)\n", [{"p2os"}]),
])
def test_real_models_diagnose(tmp_path: Path, model: Path, obs: str,
                              expected: list[set[str]]) -> None:
    theory = load_theory(model)
    assert theory.notes == ()
    assert diagnose(theory, tmp_path, obs) == [frozenset(e) for e in expected]


def test_an_empty_head_is_an_error_not_false(tmp_path: Path) -> None:
    f = tmp_path / "m.yaml"
    f.write_text("ab: AB\nnab: NAB\nprops: [a]\nrules:\n  - NAB(x) -> a\n  - 'NAB(y) ->'\n")
    with pytest.raises(UserError) as info:
        load_theory(f)
    assert f"{f}:6:" in str(info.value) and "false" in str(info.value)


def test_model_notes_are_printed_once(capsys: pytest.CaptureFixture[str]) -> None:
    assert cli.main(["model", "clauses", str(MODEL2)]) == 0
    err = capsys.readouterr().err
    assert err.count("ok(imu_data)") == 1 and "note:" in err
