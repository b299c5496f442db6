"""``dxboard report`` shows each plan-execution diagnosis in the mission band (issue 16, item 5):
from a journal written with the real ``Journal`` as ``dxboard experiment door-closed`` leaves it
(the way out of the office refused at 30 s, explained as door-closes(door_office), the new plan
opening the door), and a second run's plan error (M4); the ``Timeline`` holds each diagnosis
with its time, class and short explanation, and the chart draws its marker in its class's
colour above the mission's lanes, its label and its legend entry."""

from __future__ import annotations

from pathlib import Path

import matplotlib.image
import numpy as np
import pytest
from matplotlib.colors import to_rgb

from host.cli import main
from host.events import (
    DiagnosisRecord,
    LayerResult,
    Observation,
    Payload,
    PlanDiagnosis,
    RunStarted,
)
from host.journal import Journal
from host.layers import MISSION, SKILLS, Cause
from host.report.chart import DIAGNOSIS_STYLE, render
from host.report.diagnosis import short_explanation
from host.report.source import load_timeline
from host.report.timeline import WindowBound
from tests.report.test_mission import mission_journal

T0, MONO0 = 1_800_000_000.0, 5_000.0

DOOR_CLOSED = PlanDiagnosis(
    "m1", "m1.7", 7, "navigate(office, corridor, door_office): refused", ["exogenous event"],
    ["propagated: ~open(door_office) observed pre step 7, the knowledge base said "
     "open(door_office)"],
    "fault region: step 6 (gaps before steps 7..7), following open(door_office)",
    ["1. p=1.000  exogenous event: door-closes(door_office) before step 7"],
    ["steps 1..6: as intended", "before step 7: door-closes(door_office) happened"],
    ["~open(door_office) (observed)"], "", 0.0123)
MARKER_MISSING = PlanDiagnosis(
    "m1", "m1.5", 5, "mark_victim(v1, office): not seen", ["action fault"],
    ["local: ~marked(v1) observed post step 5"], "fault region: step 5",
    ["1. p=0.900  action fault: mark-not-placed(v1, office) at step 5",
     "2. p=0.100  exogenous event: marker-lost(v1) before step 6"], [], [], "", 0.01)
PLAN_ERROR = PlanDiagnosis(
    "m1", "m1.4", 4, "open_door(door_lab, corridor, lab): failed", ["plan error"],
    ["local: open_door failed"], "", [], [], [],
    "plan error at step 4 open_door(door_lab,corridor,lab): it ran as intended and reported "
    "failure; no fault mode or event explains it; the domain may lack (not (locked ?d)) "
    "(locked(door_lab)); the domain may lack (robot-at ?r) (robot-at(r1))", 0.02)


def door_closed_journal(path: Path) -> Path:
    """Two runs: M2's (the door closes, the way out is refused, the new plan opens it), then
    M4's plan error; the report draws the latest unless told ``--run``."""
    m = MONO0
    runs: dict[str, list[tuple[float, Payload]]] = {
        "m2": [(0.0, RunStarted("m2", "tedusar", "tcp://127.0.0.1:7000")),
               (0.2, Observation("on(hokuyo)", True, "board")),
               (0.5, DiagnosisRecord(((),))),
               (10.0, LayerResult(MISSION, "navigate", ("corridor", "office", "door_office"),
                                  True, (), m + 2.0, m + 10.0, "m1.6")),
               (30.0, LayerResult(MISSION, "navigate", ("office", "corridor", "door_office"),
                                  False, (Cause(MISSION, "refused"),), m + 29.0, m + 30.0,
                                  "m1.7")),
               (30.2, DOOR_CLOSED),
               (36.0, LayerResult(MISSION, "open_door", ("door_office", "office", "corridor"),
                                  True, (), m + 31.0, m + 36.0, "m2.1")),
               (44.0, LayerResult(SKILLS, "navigate", ("corridor",), True, (), m + 36.0,
                                  m + 44.0, "m2.2"))],
        "m4": [(100.0, RunStarted("m4", "tedusar", "tcp://127.0.0.1:7000")),
               (100.2, Observation("on(hokuyo)", True, "board")),
               (101.0, DiagnosisRecord(((),))),
               (108.0, LayerResult(MISSION, "open_door", ("door_lab", "corridor", "lab"), False,
                                   (Cause(MISSION, "failed"),), m + 104.0, m + 108.0,
                                   "m1.4")),
               (108.3, PLAN_ERROR),
               (112.0, LayerResult(MISSION, "navigate", ("lab", "corridor", "door_lab"), True,
                                   (), m + 109.0, m + 112.0, "m1.5"))],
    }
    with Journal(path) as journal:
        for events in runs.values():
            for t, payload in events:
                journal.record(payload, wall=T0 + t, mono=MONO0 + t)
    return path


def test_the_short_explanation_is_the_best_history_or_the_plan_error() -> None:
    assert short_explanation(DOOR_CLOSED) == "door-closes(door_office) before step 7"
    assert short_explanation(MARKER_MISSING) == "mark-not-placed(v1, office) at step 5"
    assert short_explanation(PLAN_ERROR) == (
        "open_door(door_lab,corridor,lab) at step 4: the domain may lack (not (locked ?d))")
    grouped = PlanDiagnosis(
        "m1", "m1.7", 7, "", ["exogenous event"], [], "",
        ["1. p=0.600  exogenous event: door-closes(door_office) between steps 3 and 7 "
         "(in one of 4 gaps), p=0.150 each"], [], [], "", 0.0)
    assert short_explanation(grouped) == (
        "door-closes(door_office) between steps 3 and 7 (in one of 4 gaps)")
    mixed = PlanDiagnosis(
        "m1", "m1.7", 7, "", ["action fault", "exogenous event"], [], "",
        ["1. p=1.000  action fault: navigate-stuck(office) at step 6; exogenous event: "
         "door-closes(door_office) before step 7"], [], [], "", 0.0)
    assert short_explanation(mixed) == ("action fault: navigate-stuck(office) at step 6; "
                                        "exogenous event: door-closes(door_office) before step 7")
    nothing = PlanDiagnosis("m1", "m1.3", 3, "", [], [], "", [], [], [], "", 0.0)
    assert short_explanation(nothing) == "nothing explains the alarm at step 3"


def test_the_timeline_holds_each_diagnosis_with_its_time_class_and_text(
        tmp_path: Path) -> None:
    journal = door_closed_journal(tmp_path / "m.sqlite")
    (m2,) = load_timeline(journal, run="m2").plan_diagnoses
    assert m2.time == pytest.approx(30.2) and (m2.step, m2.dispatch_id) == (7, "m1.7")
    assert m2.classes == ("exogenous event",) and m2.cls == "exogenous event"
    assert m2.label == "exogenous event: door-closes(door_office) before step 7"
    (m4,) = load_timeline(journal).plan_diagnoses  # the latest run: m4's, on its own axis
    assert m4.time == pytest.approx(8.3) and m4.cls == "plan error"
    assert "the domain may lack (not (locked ?d))" in m4.label
    assert load_timeline(journal, run="m2", end=WindowBound(30.0)).plan_diagnoses == ()


def test_the_chart_draws_each_diagnosis_in_the_mission_band(tmp_path: Path) -> None:
    journal = door_closed_journal(tmp_path / "m.sqlite")
    out = tmp_path / "m2.png"
    assert main(["report", str(journal), "--run", "m2", "-o", str(out)]) == 0
    timeline = load_timeline(journal, run="m2")
    layout = render(timeline, tmp_path / "again.png")
    img = matplotlib.image.imread(out)[:, :, :3]

    def colour_at(x: float, y: float, colour: str, r: int = 4) -> bool:
        patch = img[round(y) - r:round(y) + r + 1, round(x) - r:round(x) + r + 1]
        return bool((np.abs(patch - np.array(to_rgb(colour))).max(axis=2) < 0.03).any())

    event, plan_error = DIAGNOSIS_STYLE["exogenous event"][0], DIAGNOSIS_STYLE["plan error"][0]
    ((x, y),) = layout.diagnosis_px
    assert x == pytest.approx(layout.x_px(30.2))
    assert y < min(layout.layer_y_px.values()) < layout.row_y_px["hokuyo"]  # top of the band
    assert colour_at(x, y, event) and not colour_at(layout.x_px(3.0), y, event)
    assert colour_at(x, layout.layer_y_px[SKILLS], event, r=2)  # the line down the lanes
    assert not (np.abs(img - np.array(to_rgb(plan_error))).max(axis=2) < 0.03).any()

    svg = tmp_path / "m2.svg"
    assert main(["report", str(journal), "--run", "m2", "-o", str(svg)]) == 0
    text = svg.read_text()
    for drawn in ("plan diagnosis", "exogenous event: door-closes(door_office) before step 7",
                  "<!-- exogenous event -->"):  # the lane, the mark's label, the legend
        assert drawn in text, drawn

    m4 = tmp_path / "m4.png"
    assert main(["report", str(journal), "-o", str(m4)]) == 0
    layout4 = render(load_timeline(journal), tmp_path / "again4.png")
    img = matplotlib.image.imread(m4)[:, :, :3]
    ((x4, y4),) = layout4.diagnosis_px
    assert colour_at(x4, y4, plan_error) and not colour_at(x4, y4, event)


def test_a_journal_without_a_plan_diagnosis_draws_none(tmp_path: Path) -> None:
    journal = mission_journal(tmp_path / "m.sqlite")
    assert load_timeline(journal).plan_diagnoses == ()
    assert render(load_timeline(journal), tmp_path / "m.png").diagnosis_px == ()
