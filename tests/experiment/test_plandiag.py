"""Experiments M2-M4 (plan-execution diagnosis) end to end: ``dxboard experiment door-closed |
marker-missing | plan-error`` through the real command (a subprocess: the emulated robot with
its pyrobosim world, the daemon, the mission's layers; ``--fast`` boot times). Each runs the
mission fault-free and then with its event injected through the arena; the journal holds the
``PlanDiagnosis`` the page and the report read. M2: a door closed behind the robot is an
exogenous event found at a precondition check, and the new plan opens it; M3: a marker
reported placed but missing is the marking's fault mode, and the victim is marked again; M4: a
locked door on a healthy robot is a plan error naming (not (locked ?d)). No assertion is about
speed."""

from __future__ import annotations

from pathlib import Path
from typing import Any

from host.events import KbChange, PlanDiagnosis
from host.journal import JournalReader
from tests.experiment.test_experiments import experiment as run_experiment


def experiment(which: str, journal: Path) -> dict[str, Any]:
    # the same mission fault-free, with no plan-execution diagnosis, is M1's first run
    # (tests/mission/test_commands.py): here only the run with the event
    data = run_experiment(which, journal, 240, "--no-fault-free")
    assert data["experiment"] == which and set(data["runs"]) == {which}
    assert not journal.with_name(f"{journal.stem}-fault-free.sqlite").exists()
    return dict(data["runs"][which])


def journaled(journal: Path) -> list[Any]:
    with JournalReader(journal) as r:
        return [e.payload for e in r.query()]


def test_m2_a_door_closed_behind_the_robot(tmp_path: Path) -> None:
    run = experiment("door-closed", tmp_path / "m2.sqlite")
    assert run["completed"] and run["fault_s"] is not None, run  # (what happened, if not)
    d, = run["diagnoses"]
    assert d["classes"] == ["exogenous event"]
    assert d["symptoms"][0].startswith("propagated: ~open(door_office) observed pre step")
    assert d["region"].startswith("fault region:")
    assert "door-closes(door_office)" in d["histories"][0]
    assert any("door-closes(door_office) happened" in line for line in d["path"])
    assert "~open(door_office) (observed)" in d["kb"]
    assert d["new_plan"][:2] == ["open_door(door_office, office, corridor)",
                                 "navigate(office, corridor, door_office)"]
    assert d["to_diagnosis_s"] is not None and d["to_new_plan_s"] >= d["to_diagnosis_s"]
    events = journaled(tmp_path / "m2.sqlite")
    assert [e.dispatch_id for e in events if isinstance(e, PlanDiagnosis)] == [d["dispatch_id"]]


def test_m3_a_marker_reported_placed_is_missing(tmp_path: Path) -> None:
    run = experiment("marker-missing", tmp_path / "m3.sqlite")
    assert run["completed"], run
    d, = run["diagnoses"]
    assert d["classes"] == ["action fault"]
    assert d["symptoms"][0].startswith("local: ~marked(")
    assert "mark-not-placed(" in d["histories"][0]
    victim = d["histories"][0].split("mark-not-placed(")[1].split(",")[0]
    assert d["new_plan"] and d["new_plan"][0].startswith(f"mark_victim({victim}, ")
    assert any(isinstance(e, KbChange) and e.source == "sensing"
               and f"(marked {victim})" in e.removed for e in journaled(tmp_path / "m3.sqlite"))


def test_m4_a_plan_error_names_the_condition_the_domain_lacks(tmp_path: Path) -> None:
    run = experiment("plan-error", tmp_path / "m4.sqlite")
    assert not run["completed"] and "(searched lab)" in run["detail"]
    d, = run["diagnoses"]
    assert d["classes"] == ["plan error"] and d["histories"] == []
    assert "open_door(door_lab,corridor,lab)" in d["plan_error"]
    assert "the domain may lack (not (locked ?d)) (locked(door_lab))" in d["plan_error"]


def test_the_text_gives_a_delay_only_against_a_fault_free_run() -> None:
    from host.experiment.mission import MissionRun
    from host.experiment.plandiag import plan_diagnosis_text

    runs = {"fault-free": MissionRun("fault-free", True, duration_s=40.0),
            "door-closed": MissionRun("door-closed", True, duration_s=44.5)}
    text = plan_diagnosis_text("door-closed", "tedusar", True, runs)
    assert "delay +4.5 s against fault-free" in text
    assert text.endswith("no plan-execution diagnosis was made")
    del runs["fault-free"]  # --no-fault-free
    text = plan_diagnosis_text("door-closed", "tedusar", True, runs)
    assert "door-closed    completed: 44.5 s" in text and "delay" not in text
