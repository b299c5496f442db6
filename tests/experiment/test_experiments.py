"""``dxboard experiment`` end to end: both of paper 000's experiments through the real command
(a subprocess, ``--fast`` boot times), then ``dxboard report`` on each experiment's journal.

Power-up (§VI-A): the first diagnosis is the paper's 11 abnormal components (and, beyond the
paper's model, the thermal camera with its driver, reported apart), the first plan powers
each device before starting its driver (and the driver starts only after the power-up is
verified), a later plan only repairs a step that failed, both runs end all-normal, and the
one-at-a-time run never overlaps two steps while the parallel one does. Device shut-down
(§VI-B): {jaguar} is diagnosed, the repair is the paper's power_up(jaguar),
stop_node(jaguar_node), start_node(jaguar_node), and the robot ends all-normal. No assertion
is about speed.
"""

from __future__ import annotations

import functools
import itertools
import json
import shutil
import subprocess
import sys
from pathlib import Path
from typing import Any

import pytest

from host.journal import DiagnosisRecord, JournalReader
from tests.ports import clashed

ROOT = Path(__file__).resolve().parents[2]
PAPER_11 = {"jaguar", "hokuyo", "laser_alignment", "laser_alignment_node",
            "laser_alignment_control", "hector_mapping", "jaguar_node", "hokuyo_node",
            "imu_node", "jaguar_teleop_node", "joy_node"}
BEYOND_PAPER = {"thermal_camera", "thermal_camera_node"}
DRIVERS = {"jaguar": "jaguar_node", "hokuyo": "hokuyo_node",
           "laser_alignment": "laser_alignment_node", "thermal_camera": "thermal_camera_node"}


def experiment(which: str, journal: Path, timeout_s: float = 90, *extra: str) -> dict[str, Any]:
    for _ in range(3):  # the zenoh port it picked was taken meanwhile: it says so, run again
        out = subprocess.run(
            [sys.executable, "-m", "host.cli", "experiment", which, "models/tedusar", "--fast",
             "--json", "--journal", str(journal), "--timeout", f"{timeout_s:g}", *extra],
            cwd=ROOT, capture_output=True, text=True, timeout=max(240, 4 * timeout_s))
        if out.returncode == 0 or not clashed(out.stderr):
            break
        fresh_journals(journal)
    assert out.returncode == 0, out.stderr[-3000:]
    data: dict[str, Any] = json.loads(out.stdout)
    return data


def fresh_journals(journal: Path) -> None:
    """Remove a run's journal, its sidecars and its node-log directory, for a rerun."""
    for f in journal.parent.glob(journal.stem + "*"):
        if f.is_dir():
            shutil.rmtree(f)
        else:
            f.unlink()


def test_a_rerun_starts_from_no_journal_and_no_node_logs(tmp_path: Path) -> None:
    journal = tmp_path / "m2.sqlite"
    journal.write_bytes(b"x")
    (tmp_path / "m2.sqlite-wal").write_bytes(b"x")
    (tmp_path / "m2-fault-free-logs").mkdir()
    (tmp_path / "m2-fault-free-logs" / "nodes.json").write_text("{}")
    (tmp_path / "other.sqlite").write_bytes(b"x")
    fresh_journals(journal)
    assert [p.name for p in tmp_path.iterdir()] == ["other.sqlite"]


def last_diagnosis_normal(journal: Path) -> bool:
    with JournalReader(journal) as r:
        diags = [e.payload for e in r.query(kind="diagnosis")
                 if isinstance(e.payload, DiagnosisRecord)]
    assert diags, f"{journal}: no diagnosis journaled"
    return all(not d for d in diags[-1].diagnoses)


@pytest.fixture(scope="module")
def power_up(tmp_path_factory: pytest.TempPathFactory) -> tuple[dict[str, Any], Path]:
    journal = tmp_path_factory.mktemp("power-up") / "power-up.sqlite"
    return experiment("power-up", journal), journal


@pytest.fixture(scope="module")
def shutdown(tmp_path_factory: pytest.TempPathFactory) -> tuple[dict[str, Any], Path]:
    journal = tmp_path_factory.mktemp("shutdown") / "shutdown.sqlite"
    return experiment("device-shutdown", journal), journal


def told(label: str, run: dict[str, Any]) -> str:
    """``label`` and the run's plans, actions and notes, as ``dxboard journal`` shows them: what
    a failed assertion about a run prints (only then is it called), so that a failure on a busy
    machine can be read afterwards."""
    out = subprocess.run(
        [sys.executable, "-m", "host.cli", "journal", run["journal"], "--tail", "80", "--kind",
         "plan", "--kind", "action", "--kind", "note"],
        cwd=ROOT, capture_output=True, text=True, timeout=120)
    return f"{label}:\n{out.stdout[-6000:]}{out.stderr[-500:]}"


def overlapping(actions: list[dict[str, Any]]) -> bool:
    spans = sorted((a["start_s"], a["end_s"]) for a in actions)
    return any(b[0] < a[1] for a, b in itertools.pairwise(spans))


def test_power_up_diagnoses_the_papers_11_and_powers_before_drivers(
        power_up: tuple[dict[str, Any], Path]) -> None:
    data, journal = power_up
    assert data["experiment"] == "power-up" and data["paper_s"] == 30.2
    assert set(data["runs"]) == {"parallel", "sequential"}
    for label, run in data["runs"].items():
        why = functools.partial(told, label, run)
        assert set(run["paper_diagnosis"]) == PAPER_11, why()
        assert set(run["beyond_paper"]) == BEYOND_PAPER, why()
        assert set(run["first_diagnosis"]) == PAPER_11 | BEYOND_PAPER, why()
        # the first plan is the paper's: power each device, then start its driver
        plans = run["plans"]
        plan = plans[0]["steps"]
        for dev, node in DRIVERS.items():
            assert plan.index(f"power_up({dev})") < plan.index(f"start_node({node})"), why()
        assert {p.split("(")[0] for p in plan} <= {"power_up", "start_node"}, why()
        # a later plan only follows a step that failed (a busy machine can make a component
        # fail: beside a CPU hog, a hector_mapping whose map did not come within 36 s, its
        # stretched time, was restarted and then mapped), restarts what failed and runs
        # what the first plan had left
        acts = run["actions"]
        failed = {a["args"][0] for a in acts if a["state"] == "failed"}
        first_id = plans[0]["plan_id"]
        done = {f"{a['action']}({', '.join(a['args'])})" for a in acts
                if a["state"] == "succeeded" and a["plan_id"] == first_id}
        for later in plans[1:]:
            for step in later["steps"]:
                comp = step.split("(")[1].rstrip(")")
                assert comp in failed or (step in plan and step not in done), why()
        assert acts and (failed == set()) == (len(plans) == 1), why()
        # each component whose step failed was planned again and succeeded then
        again = {a["args"][0] for a in acts
                 if a["state"] == "succeeded" and a["plan_id"] != first_id}
        assert failed <= again, why()
        up_start = {a["args"][0]: a["start_s"] for a in acts if a["action"] == "power_up"}
        up_end = {a["args"][0]: a["end_s"] for a in acts if a["action"] == "power_up"}
        starts = {a["args"][0]: a["start_s"] for a in acts if a["action"] == "start_node"}
        assert set(up_end) == set(DRIVERS), why()
        for dev, node in DRIVERS.items():
            # in parallel a driver starts once its device is switched on (it retries while
            # the device boots), before the power-up is verified; one at a time, after it
            first = up_end[dev] if label == "sequential" else up_start[dev]
            assert starts[node] >= first, told(
                f"{label}: {node} started before {dev} was switched on", run)
        assert run["time_to_healthy_s"] is not None and run["repair_s"] is not None, why()
        if label == "parallel":  # the lidar's driver did not wait out the lidar's boot
            assert starts["hokuyo_node"] < up_end["hokuyo"], why()
    assert overlapping(data["runs"]["parallel"]["actions"])
    assert not overlapping(data["runs"]["sequential"]["actions"])
    assert data["parallel_vs_sequential"] is not None
    assert data["first_diagnosis"] == data["runs"]["parallel"]["first_diagnosis"]
    assert last_diagnosis_normal(journal)
    assert last_diagnosis_normal(journal.with_name("power-up-sequential.sqlite"))


def test_device_shutdown_is_repaired_with_the_papers_plan(
        shutdown: tuple[dict[str, Any], Path]) -> None:
    data, journal = shutdown
    assert data["experiment"] == "device-shutdown" and data["device"] == "jaguar"
    assert data["first_diagnosis"] == ["jaguar"]
    assert data["plan"] == ["power_up(jaguar)", "stop_node(jaguar_node)",
                            "start_node(jaguar_node)"]
    assert [(a["action"], a["args"], a["state"]) for a in data["actions"]] == [
        ("power_up", ["jaguar"], "succeeded"), ("stop_node", ["jaguar_node"], "succeeded"),
        ("start_node", ["jaguar_node"], "succeeded")]
    assert data["detected_s"] is not None and data["time_to_healthy_s"] is not None
    assert data["detected_s"] <= data["diagnosis_s"] <= data["actions"][0]["start_s"]
    assert last_diagnosis_normal(journal)


@pytest.mark.parametrize("which", ["power_up", "shutdown"])
def test_report_draws_each_experiments_journal(which: str, request: pytest.FixtureRequest,
                                               tmp_path: Path) -> None:
    _, journal = request.getfixturevalue(which)
    png = tmp_path / f"{which}.png"
    out = subprocess.run(
        [sys.executable, "-m", "host.cli", "report", str(journal), "-o", str(png),
         "--model", "models/tedusar"], cwd=ROOT, capture_output=True, text=True, timeout=120)
    assert out.returncode == 0, out.stderr[-2000:]
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_a_directory_without_a_robot_is_a_one_line_error(tmp_path: Path) -> None:
    out = subprocess.run([sys.executable, "-m", "host.cli", "experiment", "power-up",
                          str(tmp_path)], cwd=ROOT, capture_output=True, text=True, timeout=60)
    assert out.returncode == 2
    assert out.stderr.strip().count("\n") == 0 and "no system.yaml" in out.stderr


def test_no_fault_free_run_is_refused_where_there_is_none() -> None:
    out = subprocess.run([sys.executable, "-m", "host.cli", "experiment", "power-up",
                          "models/tedusar", "--no-fault-free"], cwd=ROOT, capture_output=True,
                         text=True, timeout=60)
    assert out.returncode == 2 and out.stderr.strip().count("\n") == 0, out.stderr
    assert "--no-fault-free: power-up has no fault-free run" in out.stderr
