"""What a person reads in ``dxboard report``'s image is legible and true (issue 26 item 6).

Every text of the figure is measured with matplotlib's own text extents on the renderer that
draws it: no two texts overlap and none leaves the figure (the subtitle was clipped, the "all
normal" labels of a loaded machine's short-lived diagnoses were drawn over each other). And a
diagnosis retracted within the repair debounce (a load artefact: nothing was repaired) is drawn
as retracted, not red like a real fault.
"""

from __future__ import annotations

import itertools
from pathlib import Path

import matplotlib.image
import numpy as np
import pytest
from matplotlib.colors import to_rgb
from matplotlib.figure import Figure
from matplotlib.text import Text
from matplotlib.transforms import Bbox

from host.report.chart import STATE_COLORS, draw, render
from host.report.source import load_timeline
from host.report.timeline import HealthState, Timeline
from tests.report.journals import TEDUSAR_DIR, device_shut_down, load_flaps, power_up


def texts(fig: Figure) -> list[tuple[str, Bbox]]:
    """Every visible, non-empty text of the figure (legend included) with its box in pixels."""
    fig.canvas.draw()  # texts are placed (axis labels, legend) as they are drawn
    renderer = fig.canvas.get_renderer()  # type: ignore[attr-defined]
    undrawn: set[int] = set()  # tick labels of ticks outside the view, which are not drawn
    for ax in fig.axes:
        for axis in (ax.xaxis, ax.yaxis):
            lo, hi = sorted(ax.get_xlim() if axis is ax.xaxis else ax.get_ylim())
            for tick in axis.get_major_ticks() + axis.get_minor_ticks():
                if not lo - 1e-9 <= tick.get_loc() <= hi + 1e-9:
                    undrawn |= {id(tick.label1), id(tick.label2)}
    found = []
    for t in fig.findobj(Text):
        if t.get_visible() and t.get_text().strip() and id(t) not in undrawn:
            found.append((t.get_text(), t.get_window_extent(renderer)))
    return found


def assert_legible(fig: Figure) -> None:
    boxes = texts(fig)
    assert boxes
    frame = fig.bbox
    for text, box in boxes:
        assert (box.x0 >= frame.x0 - 0.5 and box.x1 <= frame.x1 + 0.5
                and box.y0 >= frame.y0 - 0.5 and box.y1 <= frame.y1 + 0.5), \
            f"{text!r} leaves the figure: {box} not in {frame}"
    for (a, ba), (b, bb) in itertools.combinations(boxes, 2):
        overlap_w = min(ba.x1, bb.x1) - max(ba.x0, bb.x0)
        overlap_h = min(ba.y1, bb.y1) - max(ba.y0, bb.y0)
        assert overlap_w <= 0.5 or overlap_h <= 0.5, f"{a!r} overlaps {b!r}: {ba} / {bb}"


def timeline_of(journal: Path, *, model: bool = True) -> Timeline:
    return load_timeline(journal, model=TEDUSAR_DIR if model else None)


@pytest.mark.parametrize("make", [power_up, device_shut_down, load_flaps])
def test_no_text_of_the_chart_overlaps_another_or_leaves_the_figure(
        tmp_path: Path, make: object) -> None:
    journal = make(tmp_path / "j.sqlite")  # type: ignore[operator]
    fig, _layout = draw(timeline_of(journal))
    assert_legible(fig)


def test_a_long_subtitle_is_not_clipped(tmp_path: Path) -> None:
    journal = power_up(tmp_path / "a-journal-with-a-rather-long-name.sqlite", failing=True,
                       run="20261123T210826-3fa2")
    fig, _layout = draw(timeline_of(journal))
    assert_legible(fig)


def test_diagnoses_retracted_within_the_debounce_are_drawn_as_such(tmp_path: Path) -> None:
    t = timeline_of(load_flaps(tmp_path / "j.sqlite"))
    imu = t.row("imu")
    # the five blips are retracted, not abnormal; the base's real fault is abnormal
    assert imu.time_in(HealthState.ABNORMAL) == 0.0
    assert sum(1 for iv in imu.intervals if iv.state is HealthState.RETRACTED) == 5
    assert t.row("jaguar").state_at(31.0) is HealthState.ABNORMAL
    # a retraction is no recovery: the only "all normal" is after the real repair
    assert [round(r.normal_at, 1) for r in t.recoveries] == [35.0]
    out = tmp_path / "j.png"
    layout = render(t, out)
    img = matplotlib.image.imread(out)
    y = round(layout.row_y_px["imu"])

    def colour_at(sec: float) -> np.ndarray:
        return img[y, round(layout.x_px(sec))][:3]  # type: ignore[no-any-return]

    def near(pixel: np.ndarray, colour: str) -> bool:
        return bool(np.abs(pixel - np.array(to_rgb(colour))).max() < 0.03)

    blip = colour_at(4.2)
    assert not near(blip, STATE_COLORS[HealthState.ABNORMAL]), blip
    assert near(blip, STATE_COLORS[HealthState.RETRACTED]) or near(blip, "#ffffff"), blip
    jrow = round(layout.row_y_px["jaguar"])
    assert near(img[jrow, round(layout.x_px(31.0))][:3], STATE_COLORS[HealthState.ABNORMAL])
