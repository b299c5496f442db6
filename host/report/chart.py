"""Drawing a ``Timeline`` with matplotlib (Agg, no display): the paper's figures 5 and 6.

The figure, top to bottom: a title (robot and journal) with a subtitle (journal ids, start
time, clock); when the journal holds a mission (paper 001), its layers as three lanes — the
mission's actions (labelled where they fit), their behaviour trees (a tree held by its guard
while layer 0 repairs hatched amber) and the skills, failures hatched, and above them each
plan-execution diagnosis: a marker at its time, shaped and coloured by its class (exogenous
event, action fault, plan error, component fault), a dotted line down through the lanes, and
its class with the short explanation beside it; the repair actions,
one bar per action from its start to its end on a few lanes (packed so that no two labels
overlap), each labelled with its call and, unless it succeeded, its outcome (failed and
timed-out actions hatched in their own colours); then one row per
component in groups (hardware, drivers, nodes, other), each a band coloured by its state over
time (normal pale green, abnormal red, unknown hatched grey, and a thin amber band where a
diagnosis was retracted within the repair debounce: a load artefact, not a fault); a dashed
green line where the whole system became normal again, labelled with the time and how long the
repair took from its first action (labels never drawn over each other: shortened or left
out); the time axis in seconds; a legend. Faint vertical guides carry each action's start down
through the rows, so cause and effect line up.

Sizes are fixed in inches (the height grows with the rows and lanes; a title or subtitle wider
than the figure is set smaller), so a chart is as legible in a paper as on a screen; ``draw``
makes the figure, ``render`` writes it and returns a ``Layout`` telling where (in pixels) each
row and each second lies, which the tests use to check the colours of the image.
"""

from __future__ import annotations

import logging
import os
from collections.abc import Callable
from dataclasses import dataclass, field
from datetime import UTC, datetime
from pathlib import Path

import matplotlib

# Figure.savefig needs no pyplot; Agg all the same, so nothing here ever wants a display
matplotlib.use("Agg")

from matplotlib.axes import Axes
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure
from matplotlib.font_manager import FontProperties
from matplotlib.lines import Line2D
from matplotlib.patches import Patch, Rectangle
from matplotlib.textpath import TextToPath
from matplotlib.ticker import MaxNLocator

from host.report.diagnosis import UNEXPLAINED, DiagnosisMark
from host.report.mission import LANE_NAMES, LANES
from host.report.timeline import (
    GROUP_ORDER,
    RUNNING,
    ActionSpan,
    ComponentRow,
    HealthState,
    Timeline,
)

log = logging.getLogger(__name__)

# colours (also what the tests look for in the image)
STATE_COLORS = {HealthState.NORMAL: "#bfe3c6", HealthState.ABNORMAL: "#d7263d",
                HealthState.UNKNOWN: "#e3e3e3",
                HealthState.RETRACTED: "#f2c46d"}  # retracted: amber, outlined, never the fault red
STATE_LABELS = {HealthState.RETRACTED: "retracted within the debounce (not repaired)"}
OUTCOME_COLORS = {"succeeded": "#2b6cb0", "failed": "#e8590c", "timeout": "#b7791f",
                  RUNNING: "#7f8c9a"}
OUTCOME_HATCH = {"failed": "xxxx", "timeout": "....", RUNNING: "////"}
RECOVERY_COLOR = "#1e7b34"
MISSION_OK = "#6b46c1"  # a mission layer's command that succeeded
HOLD_COLOR = "#d69e2e"  # a behaviour tree held while layer 0 repairs
# a plan-execution diagnosis by its class: (colour, marker)
DIAGNOSIS_STYLE = {"exogenous event": ("#0f8b8d", "D"), "action fault": ("#c2185b", "X"),
                   "plan error": ("#1a365d", "s"), "component fault": ("#d7263d", "o"),
                   UNEXPLAINED: ("#7f8c9a", "o")}
TEXT = "#222222"
MUTED = "#666666"

FORMATS = (".png", ".svg")

# the geometry, in inches (fonts in points)
_W = 10.0
_LEFT, _RIGHT = 2.05, 0.3
_TITLE_H = 0.62
_LANE_H = 0.27
_MISSION_LANE_H = 0.36
_ACTIONS_PAD = 0.12
_GAP = 0.1
_RECOVERY_H = 0.3  # the strip between actions and rows that holds "all normal at ..."
_ROW_H = 0.27
_HEADER_H = 0.25
_AXIS_H = 0.5
_LEGEND_H = 0.42
_LABEL_PT = 7.5
_ROW_PT = 8.5
_GROUP_PT = 8.0
_DPI = 150


@dataclass(frozen=True)
class Layout:
    """Where things landed in the image: pixels from the top-left corner."""

    width_px: int
    height_px: int
    row_y_px: dict[str, float]
    lane_count: int
    x_px: Callable[[float], float]
    layer_y_px: dict[int, float] = field(default_factory=dict)  # the mission's lanes
    diagnosis_px: tuple[tuple[float, float], ...] = ()  # (x, y) of each plan diagnosis


def _text_width_in(text: str, size_pt: float, bold: bool = False) -> float:
    props = FontProperties(size=size_pt, weight="bold" if bold else "normal")
    width, _h, _d = TextToPath().get_text_width_height_descent(text, props, ismath=False)
    return float(width) / 72.0


def _fitted_pt(text: str, size_pt: float, bold: bool = False) -> float:
    """``size_pt``, or smaller so that ``text`` fits the figure's width with a margin."""
    room = _W - 0.3
    width = _text_width_in(text, size_pt, bold=bold)
    return size_pt if width <= room else size_pt * room / width


def action_label(span: ActionSpan) -> str:
    """The text next to an action's bar: its call, and its outcome unless it succeeded."""
    if span.ok:
        return span.label
    mark = {"failed": "\u2717 failed", "timeout": "\u2717 timeout", RUNNING: "\u2026 running"}
    return f"{span.label}  {mark.get(span.outcome, span.outcome)}"


@dataclass(frozen=True)
class _Placed:
    span: ActionSpan
    lane: int
    text: str
    text_x: float  # data x of the label's anchor
    align: str  # "left" (after the bar) or "right" (before it)


def _fit(items: list[tuple[float, float, str, bool]], end: float, sec_per_in: float
         ) -> list[tuple[int, float, str]]:
    """Lanes for (start, end, label, bold) items, first fit, so no two of them or their labels
    overlap: per item its lane, its label's anchor (data x) and its alignment."""
    gap = 0.06 * sec_per_in
    lanes: list[float] = []  # per lane: where it is free from
    placed: list[tuple[int, float, str]] = []
    for start, stop, text, bold in items:
        w = _text_width_in(text, _LABEL_PT, bold=bold) * sec_per_in
        if stop + gap + w <= end or (start - gap - w < 0 and end - stop >= start):
            lo, hi, tx, align = start, stop + gap + w, stop + gap, "left"
        else:
            lo, hi, tx, align = start - gap - w, stop, start - gap, "right"
        lane = next((i for i, free in enumerate(lanes) if lo >= free), len(lanes))
        if lane == len(lanes):
            lanes.append(0.0)
        lanes[lane] = hi + 2 * gap
        placed.append((lane, tx, align))
    return placed


def _pack(actions: tuple[ActionSpan, ...], end: float, sec_per_in: float) -> list[_Placed]:
    """Lanes for the actions, so no two bars or labels overlap."""
    items = [(s.start, end if s.end is None else max(s.end, s.start + 0.04 * sec_per_in),
              action_label(s), not s.ok) for s in actions]
    return [_Placed(s, lane, item[2], tx, align)
            for s, item, (lane, tx, align) in zip(actions, items,
                                                  _fit(items, end, sec_per_in), strict=True)]


def _pack_diagnoses(marks: tuple[DiagnosisMark, ...], end: float, sec_per_in: float
                    ) -> list[tuple[int, float, str, str]]:
    """Lanes for the plan diagnoses' markers and labels (elided where they do not fit):
    per mark its lane, its label's anchor, alignment and text."""
    half = 0.05 * sec_per_in  # half a marker's width
    items = []
    for m in marks:
        room = (max(end - m.time, m.time) - 2.5 * half) / sec_per_in  # inches beside it
        label = m.label
        while len(label) > 8 and _text_width_in(label, _LABEL_PT, bold=True) > room:
            label = label[:-2] + "\u2026"  # elided to fit: the journal holds it whole
        items.append((m.time - half, m.time + half, label, True))
    return [(lane, tx, align, item[2])
            for item, (lane, tx, align) in zip(items, _fit(items, end, sec_per_in), strict=True)]


def _row_slots(rows: tuple[ComponentRow, ...]) -> list[tuple[str, str]]:
    """Top to bottom: ("group", name) headers and ("row", component) rows."""
    slots: list[tuple[str, str]] = []
    groups = [g for g in GROUP_ORDER if any(r.group is g for r in rows)]
    for g in groups:
        if len(groups) > 1 or g.value != "other":
            slots.append(("group", g.value))
        slots.extend(("row", r.name) for r in rows if r.group is g)
    return slots


def _title(t: Timeline) -> tuple[str, str]:
    head = f"{t.robot}: {t.name}" if t.robot else t.name
    when = datetime.fromtimestamp(t.origin_wall, UTC).strftime("%Y-%m-%d %H:%M:%S UTC")
    n_fail = sum(1 for a in t.actions if not a.ok)
    acts = f"{len(t.actions)} repair action{'s' if len(t.actions) != 1 else ''}"
    if n_fail:
        acts += f" ({n_fail} not succeeded)"
    run = f"run {t.run}, " if t.run else ""
    sub = (f"{run}journal entries #{t.first_id}\u2013#{t.last_id}, t = 0 at {when}  \u00b7  "
           f"{len(t.rows)} components  \u00b7  {acts}")
    return head, sub


def render(t: Timeline, out: str | os.PathLike[str], *, title: str | None = None,
           dpi: int = _DPI) -> Layout:
    """Draw ``t`` into ``out`` (PNG or SVG by its suffix); returns where things landed."""
    path = Path(out)
    fmt = path.suffix.lower()
    if fmt not in FORMATS:
        raise ValueError(f"cannot write {path.suffix or 'a file without suffix'}")
    fig, layout = draw(t, title=title, dpi=dpi)
    fig.savefig(path, format=fmt[1:], dpi=dpi, facecolor="white",
                metadata=None if fmt == ".svg" else {"Software": "dxboard report"})
    return layout


def draw(t: Timeline, *, title: str | None = None, dpi: int = _DPI) -> tuple[Figure, Layout]:
    """The figure of ``t`` (not yet written) and where things land in it."""
    end = max(t.end, 1e-3)
    axw = _W - _LEFT - _RIGHT
    sec_per_in = end / axw
    placed = _pack(t.actions, end, sec_per_in)
    lanes = max([p.lane + 1 for p in placed], default=1)
    slots = _row_slots(t.rows)
    rows_h = sum(_HEADER_H if kind == "group" else _ROW_H for kind, _ in slots)
    act_h = lanes * _LANE_H + 2 * _ACTIONS_PAD
    gap = _RECOVERY_H if t.recoveries else _GAP
    legend_rows = 1 if _legend_count(t) <= 6 else 2
    legend_h = _LEGEND_H + (legend_rows - 1) * 0.2
    diag = _pack_diagnoses(t.plan_diagnoses, end, sec_per_in)
    diag_lanes = max([p[0] + 1 for p in diag], default=0)
    mis_h = (len(LANES) * _MISSION_LANE_H + diag_lanes * _LANE_H + 2 * _ACTIONS_PAD
             if t.mission or t.plan_diagnoses else 0.0)
    height = _TITLE_H + mis_h + act_h + gap + rows_h + _AXIS_H + legend_h

    fig = Figure(figsize=(_W, height), dpi=dpi)
    FigureCanvasAgg(fig)  # a renderer to measure texts with (the tests do)
    fig.patch.set_facecolor("white")
    rows_bottom = _AXIS_H + legend_h
    ax = fig.add_axes((_LEFT / _W, rows_bottom / height, axw / _W, rows_h / height))
    top = fig.add_axes((_LEFT / _W, (rows_bottom + rows_h + gap) / height, axw / _W,
                        act_h / height), sharex=ax)
    layer_y: dict[int, float] = {}
    diag_y: list[float] = []
    if mis_h:
        mis_bottom = rows_bottom + rows_h + gap + act_h
        mis = fig.add_axes((_LEFT / _W, mis_bottom / height, axw / _W, mis_h / height),
                           sharex=ax)
        lane_y = _draw_mission(mis, t, mis_h - diag_lanes * _LANE_H, axw, sec_per_in)
        layer_y = {layer: mis_bottom + yc for layer, yc in lane_y.items()}
        diag_y = [mis_bottom + yc for yc in _draw_diagnoses(mis, t, diag, mis_h, axw)]
    head, sub = _title(t)
    head = title or head
    fig.text(0.5, 1 - 0.2 / height, head, ha="center", va="center",
             fontsize=_fitted_pt(head, 13, bold=True), fontweight="bold", color=TEXT)
    fig.text(0.5, 1 - 0.45 / height, sub, ha="center", va="center",
             fontsize=_fitted_pt(sub, 8), color=MUTED)

    # --- component rows (y in inches from the bottom of the rows axis) ----------------------
    row_y: dict[str, float] = {}
    y = rows_h
    for kind, name in slots:
        h = _HEADER_H if kind == "group" else _ROW_H
        y -= h
        if kind == "group":
            ax.text(-_LEFT / axw + 0.08 / axw, y + h * 0.45, name.upper(),
                    transform=_blend(ax), ha="left", va="center", fontsize=_GROUP_PT,
                    fontweight="bold", color=MUTED)
            if y + h < rows_h - 1e-9:
                ax.axhline(y + h, color="#999999", lw=0.8, zorder=3)
            continue
        row = t.row(name)
        row_y[name] = y + h / 2
        for iv in row.intervals:
            if iv.state is HealthState.RETRACTED:  # thin: a verdict taken back, not a fault's band
                ax.add_patch(Rectangle((iv.start, y + 0.3 * h), iv.duration, 0.4 * h,
                                       facecolor=STATE_COLORS[iv.state], lw=0, zorder=2))
                continue
            ax.add_patch(Rectangle(
                (iv.start, y + 0.14 * h), iv.duration, 0.72 * h,
                facecolor=STATE_COLORS[iv.state], edgecolor="white" if iv.state is
                HealthState.UNKNOWN else "none",
                hatch="////" if iv.state is HealthState.UNKNOWN else None,
                lw=0, zorder=2))
        ax.text(-0.1 / axw, y + h / 2, name, transform=_blend(ax), ha="right", va="center",
                fontsize=_ROW_PT, color=TEXT)
    ax.set_ylim(0, rows_h)
    ax.set_yticks([])
    ax.set_xlim(0, end)
    ax.xaxis.set_major_locator(MaxNLocator(nbins=12, steps=[1, 2, 2.5, 5, 10]))
    ax.grid(axis="x", color="#e6e6e6", lw=0.6, zorder=0)
    ax.set_axisbelow(True)
    ax.tick_params(axis="x", labelsize=8.5, colors=TEXT)
    origin = f"the window ({t.window})" if t.window else (f"run {t.run}" if t.run else
                                                           "the journal")
    ax.set_xlabel(f"time since the start of {origin} [s]", fontsize=9, color=TEXT)
    for side in ("top", "right", "left"):
        ax.spines[side].set_visible(False)

    # --- actions along the top ----------------------------------------------------------------
    top.set_ylim(0, act_h)
    top.set_yticks([])
    top.tick_params(axis="x", bottom=False, labelbottom=False)
    for side in ("top", "right", "left"):
        top.spines[side].set_visible(False)
    top.spines["bottom"].set_color("#bbbbbb")
    top.text(-0.1 / axw, act_h / 2, "repair actions", transform=_blend(top), ha="right",
             va="center", fontsize=_GROUP_PT, fontweight="bold", color=MUTED)
    for p in placed:
        s = p.span
        color = OUTCOME_COLORS.get(s.outcome, OUTCOME_COLORS["failed"])
        yc = act_h - _ACTIONS_PAD - (p.lane + 0.5) * _LANE_H
        bar_end = end if s.end is None else max(s.end, s.start + 0.04 * sec_per_in)
        top.add_patch(Rectangle((s.start, yc - 0.07), bar_end - s.start, 0.14,
                                facecolor=color if s.ok else "white", edgecolor=color,
                                hatch=OUTCOME_HATCH.get(s.outcome), lw=1.0, zorder=3))
        top.text(p.text_x, yc, p.text, ha=p.align, va="center", fontsize=_LABEL_PT,
                 color=TEXT if s.ok else color, fontweight="normal" if s.ok else "bold",
                 zorder=6, bbox={"boxstyle": "square,pad=0.1", "facecolor": "white",
                                 "edgecolor": "none"})
        ax.axvline(s.start, color=color, lw=0.6, alpha=0.35, ls=(0, (2, 2)), zorder=1)
    for plan in t.plans:
        top.plot([plan.time], [0.045], marker="^", ms=4.5, color=MUTED, zorder=3,
                 clip_on=False)

    # --- all normal again -------------------------------------------------------------------
    taken: list[tuple[float, float]] = []  # data x extents of the labels placed
    for r in t.recoveries:
        top.axvline(r.normal_at, color=RECOVERY_COLOR, lw=1.4, ls=(0, (5, 2)), zorder=5)
        ax.plot([r.normal_at] * 2, [0, rows_h + gap], color=RECOVERY_COLOR, lw=1.4,
                ls=(0, (5, 2)), zorder=5, clip_on=False)
        short = f"all normal at {r.normal_at:.1f} s"
        long = short if r.repair_s is None else (
            f"{short}  ({r.repair_s:.1f} s after the first repair action)")
        right_half = r.normal_at > 0.5 * end
        # the long label if it fits among the others, else the short one, on the side with
        # more room first; a label with no room is left out (the line and the legend say it)
        tries = [(text, left) for text in (long, short) for left in (right_half, not right_half)]
        for text, left in tries:
            anchor = r.normal_at + (-1 if left else 1) * 0.07 * sec_per_in
            w = (_text_width_in(text, 8.5, bold=True) + 0.1) * sec_per_in
            lo, hi = (anchor - w, anchor) if left else (anchor, anchor + w)
            if (lo >= -_LEFT * sec_per_in and hi <= end + _RIGHT * sec_per_in
                    and all(hi <= a or lo >= b for a, b in taken)):
                taken.append((lo, hi))
                ax.text(anchor, rows_h + gap / 2, text, ha="right" if left else "left",
                        va="center", fontsize=8.5, color=RECOVERY_COLOR, fontweight="bold",
                        zorder=6, clip_on=False)
                break

    _legend(fig, t, height, legend_rows)

    def x_px(sec: float) -> float:
        return (_LEFT + sec / sec_per_in) * dpi

    row_px = {n: (height - rows_bottom - yy) * dpi for n, yy in row_y.items()}
    return fig, Layout(round(_W * dpi), round(height * dpi), row_px, lanes, x_px,
                       {n: (height - yy) * dpi for n, yy in layer_y.items()},
                       tuple((x_px(m.time), (height - yy) * dpi)
                             for m, yy in zip(t.plan_diagnoses, diag_y, strict=True)))


def _draw_mission(mis: Axes, t: Timeline, mis_h: float, axw: float, sec_per_in: float
                  ) -> dict[int, float]:
    """The mission's layers (paper 001) as lanes above the repair actions: mission actions,
    their behaviour trees (holds hatched), skills; failures in the failed colour. ``mis_h`` is
    the height from the axes' bottom the lanes take (the diagnoses' lanes lie above it)."""
    mis.set_yticks([])
    mis.tick_params(axis="x", bottom=False, labelbottom=False)
    for side in ("top", "right", "left"):
        mis.spines[side].set_visible(False)
    mis.spines["bottom"].set_color("#bbbbbb")
    lane_y = {layer: mis_h - _ACTIONS_PAD - (i + 0.5) * _MISSION_LANE_H
              for i, layer in enumerate(LANES)}
    for layer, yc in lane_y.items():
        mis.text(-0.1 / axw, yc, LANE_NAMES[layer], transform=_blend(mis), ha="right",
                 va="center", fontsize=_GROUP_PT, fontweight="bold", color=MUTED)
    for s in t.mission:
        if s.layer not in lane_y:
            continue
        yc = lane_y[s.layer]
        width = max(s.end - s.start, 0.04 * sec_per_in)
        if s.held:
            mis.add_patch(Rectangle((s.start, yc - 0.09), width, 0.18, facecolor="white",
                                    edgecolor=HOLD_COLOR, hatch="////", lw=1.0, zorder=4))
            continue
        color = MISSION_OK if s.ok else OUTCOME_COLORS["failed"]
        mis.add_patch(Rectangle((s.start, yc - 0.07), width, 0.14,  # white edges part steps
                                facecolor=color if s.ok else "white",
                                edgecolor="white" if s.ok else color,
                                hatch=None if s.ok else OUTCOME_HATCH["failed"], lw=0.8,
                                zorder=3))
        if s.layer == LANES[0]:
            label = s.label.split("(")[0]
            if _text_width_in(label, 6.5) < width / sec_per_in:
                mis.text(s.start + width / 2, yc + 0.16, label, ha="center", va="center",
                         fontsize=6.5, color=TEXT, zorder=6)
    return lane_y


def _draw_diagnoses(mis: Axes, t: Timeline, placed: list[tuple[int, float, str, str]],
                    mis_h: float, axw: float) -> list[float]:
    """The plan diagnoses in lanes at the top of the mission band: a marker each (its class's
    shape and colour), a dotted line down through the layers, and its label; their y."""
    mis.set_ylim(0, mis_h)
    if t.plan_diagnoses:
        lanes = max(p[0] for p in placed) + 1
        mis.text(-0.1 / axw, mis_h - _ACTIONS_PAD - lanes * _LANE_H / 2, "plan diagnosis",
                 transform=_blend(mis), ha="right", va="center", fontsize=_GROUP_PT,
                 fontweight="bold", color=MUTED)
    ys = []
    for m, (lane, tx, align, text) in zip(t.plan_diagnoses, placed, strict=True):
        color, marker = DIAGNOSIS_STYLE.get(m.cls, DIAGNOSIS_STYLE[UNEXPLAINED])
        yc = mis_h - _ACTIONS_PAD - (lane + 0.5) * _LANE_H
        mis.plot([m.time, m.time], [0, yc], color=color, lw=1.0, ls=(0, (1, 1.5)), zorder=5)
        mis.plot([m.time], [yc], marker=marker, ms=6.5, color=color, ls="none", zorder=7)
        mis.text(tx, yc, text, ha=align, va="center", fontsize=_LABEL_PT, color=color,
                 fontweight="bold", zorder=6, bbox={"boxstyle": "square,pad=0.1",
                                                    "facecolor": "white", "edgecolor": "none"})
        ys.append(yc)
    return ys


def _blend(ax: Axes) -> matplotlib.transforms.Transform:
    """x in axes fractions, y in the axis' data units (inches here)."""
    return matplotlib.transforms.blended_transform_factory(ax.transAxes, ax.transData)


def _legend_count(t: Timeline) -> int:
    states = {iv.state for r in t.rows for iv in r.intervals}
    return (len(states) + len({a.outcome for a in t.actions}) + bool(t.plans)
            + bool(t.recoveries) + bool(t.mission) + any(s.held for s in t.mission)
            + len({m.cls for m in t.plan_diagnoses}))


def _legend(fig: Figure, t: Timeline, height: float, rows: int) -> None:
    states = [s for s in HealthState if any(iv.state is s for r in t.rows for iv in r.intervals)]
    handles: list[Patch | Line2D] = [
        Patch(facecolor=STATE_COLORS[s], edgecolor="white" if s is HealthState.UNKNOWN else "none",
              hatch="////" if s is HealthState.UNKNOWN else None,
              label=STATE_LABELS.get(s, s.value))
        for s in states]
    outcomes = sorted({a.outcome for a in t.actions},
                      key=lambda o: list(OUTCOME_COLORS).index(o) if o in OUTCOME_COLORS else 9)
    for o in outcomes:
        c = OUTCOME_COLORS.get(o, OUTCOME_COLORS["failed"])
        handles.append(Patch(facecolor=c if o == "succeeded" else "white", edgecolor=c,
                             hatch=OUTCOME_HATCH.get(o), label=f"action {o}"))
    if t.mission:
        handles.append(Patch(facecolor=MISSION_OK, edgecolor=MISSION_OK, label="mission step"))
    if any(s.held for s in t.mission):
        handles.append(Patch(facecolor="white", edgecolor=HOLD_COLOR, hatch="////",
                             label="tree held"))
    for cls in dict.fromkeys(m.cls for m in t.plan_diagnoses):
        color, marker = DIAGNOSIS_STYLE.get(cls, DIAGNOSIS_STYLE[UNEXPLAINED])
        handles.append(Line2D([], [], marker=marker, ls="none", color=color, ms=6,
                              label=cls if cls != UNEXPLAINED else "diagnosis: unexplained"))
    if t.plans:
        handles.append(Line2D([], [], marker="^", ls="none", color=MUTED, label="plan made"))
    if t.recoveries:
        handles.append(Line2D([], [], color=RECOVERY_COLOR, ls=(0, (5, 2)), lw=1.4,
                              label="all normal"))
    fig.legend(handles=handles, loc="lower center", ncol=-(-len(handles) // rows), fontsize=8,
               frameon=False, bbox_to_anchor=(0.5, 0.02 / height),
               handlelength=1.8, columnspacing=1.4)
