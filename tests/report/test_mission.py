"""``dxboard report`` draws a mission's layers above the components (paper 001): the mission's
actions, their behaviour trees with the hold while layer 0 repaired, and the skills, from a
journal written with the real ``Journal``: the lidar hangs during a navigation from 12 s, the
tree holds from 12.5 s to 16 s while layer 0 power-cycles it, the navigation resumes."""

from __future__ import annotations

from pathlib import Path

import matplotlib.image
import numpy as np
from matplotlib.colors import to_rgb

from host.cli import main
from host.events import (
    ActionRecord,
    ActionState,
    DiagnosisRecord,
    LayerResult,
    PlanRecord,
    PlanStep,
    TreeChange,
)
from host.journal import Journal
from host.layers import EXECUTIVE, MISSION, SKILLS, Cause
from host.report.chart import HOLD_COLOR, MISSION_OK, OUTCOME_COLORS, render
from host.report.source import load_timeline

T0, MONO0 = 1_800_000_000.0, 5_000.0
NAV = ("corridor", "office", "door_office")


def mission_journal(path: Path) -> Path:
    m = MONO0
    events = [
        (0.0, DiagnosisRecord(((),))),
        (5.0, LayerResult(MISSION, "level_laser", (), True, (), m + 4.0, m + 5.0, "m1.1")),
        (12.2, DiagnosisRecord((("hokuyo",),))),
        (12.3, PlanRecord("p1", (PlanStep("power_cycle", ("hokuyo",)),), ("hokuyo",))),
        (12.5, TreeChange("m1.2", "navigate available", "RUNNING", "SUCCESS", 40,
                          "holding: layer 0: hokuyo repairing")),
        (12.5, LayerResult(SKILLS, "navigate", ("office",), False,
                           (Cause(SKILLS, "navigate canceled"),), m + 6.0, m + 12.5, "m1.2")),
        (15.5, ActionRecord("a1", "power_cycle", ("hokuyo",), ActionState.SUCCEEDED,
                            T0 + 12.4, T0 + 15.5, "p1")),
        (15.8, DiagnosisRecord(((),))),
        (16.0, TreeChange("m1.2", "navigate available", "SUCCESS", "RUNNING", 75)),
        (20.0, LayerResult(SKILLS, "navigate", ("office",), True, (), m + 16.0, m + 20.0,
                           "m1.2")),
        (20.0, LayerResult(EXECUTIVE, "navigate", NAV, True, (), m + 6.0, m + 20.0, "m1.2")),
        (20.0, LayerResult(MISSION, "navigate", NAV, True, (), m + 6.0, m + 20.0, "m1.2")),
        (24.0, LayerResult(MISSION, "search_room", ("office",), False,
                           (Cause(MISSION, "failed"),), m + 20.0, m + 24.0, "m1.3")),
    ]
    with Journal(path) as journal:
        for t, payload in events:
            journal.record(payload, wall=T0 + t, mono=MONO0 + t)
    return path


def test_the_timeline_holds_each_layers_commands_and_the_hold(tmp_path: Path) -> None:
    t = load_timeline(mission_journal(tmp_path / "m.sqlite"))
    by = {(s.layer, s.label, s.held): s for s in t.mission}
    nav = by[(MISSION, "navigate(corridor, office, door_office)", False)]
    assert (nav.start, nav.end, nav.ok) == (6.0, 20.0, True)
    hold = by[(EXECUTIVE, "navigate available", True)]
    assert (hold.start, hold.end) == (12.5, 16.0) and "hokuyo" in hold.why
    assert not by[(MISSION, "search_room(office)", False)].ok
    assert [a.label for a in t.actions] == ["power_cycle(hokuyo)"]


def test_the_chart_draws_the_mission_above_the_components(tmp_path: Path) -> None:
    journal = mission_journal(tmp_path / "m.sqlite")
    out = tmp_path / "m.png"
    assert main(["report", str(journal), "-o", str(out)]) == 0
    layout = render(load_timeline(journal), tmp_path / "again.png")
    img = matplotlib.image.imread(out)[:, :, :3]

    def near(layer: int, t: float, color: str) -> bool:
        y, x = round(layout.layer_y_px[layer]), round(layout.x_px(t))
        patch = img[y - 8:y + 9, x - 4:x + 5]
        return bool((np.abs(patch - np.array(to_rgb(color))).max(axis=2) < 0.03).any())

    assert set(layout.layer_y_px) == {MISSION, EXECUTIVE, SKILLS}
    assert max(layout.layer_y_px.values()) < min(layout.row_y_px.values())  # above the rows
    assert near(MISSION, 10.0, MISSION_OK) and near(EXECUTIVE, 8.0, MISSION_OK)
    assert near(EXECUTIVE, 14.0, HOLD_COLOR) and not near(EXECUTIVE, 18.0, HOLD_COLOR)
    assert near(SKILLS, 18.0, MISSION_OK) and not near(SKILLS, 14.0, MISSION_OK)
    assert near(MISSION, 22.0, OUTCOME_COLORS["failed"])


def test_a_hold_keeps_every_reason_it_gave(tmp_path: Path) -> None:
    # on a busy machine the guard holds first on the topic alone, before layer 0's diagnosis
    # names the lidar (CI, stop 31): the hold's reason must still name the lidar
    path = tmp_path / "m.sqlite"
    with Journal(path) as journal:
        for t, payload in [
            (0.0, DiagnosisRecord(((),))),
            (12.0, TreeChange("m1.2", "navigate available", "RUNNING", "SUCCESS", 40,
                              "holding: layer 0: /scan down")),
            (12.2, DiagnosisRecord((("hokuyo",),))),
            (12.5, TreeChange("m1.2", "navigate available", "RUNNING", "RUNNING", 41,
                              "holding: layer 0: hokuyo repairing (/scan down)")),
            (16.0, TreeChange("m1.2", "navigate available", "SUCCESS", "RUNNING", 75)),
        ]:
            journal.record(payload, wall=T0 + t, mono=MONO0 + t)
    [hold] = [s for s in load_timeline(path).mission if s.held]
    assert (hold.start, hold.end) == (12.0, 16.0)
    assert "/scan down" in hold.why and "hokuyo repairing" in hold.why
