"""``dxboard report`` draws valid PNG and SVG timelines, with the colours where they belong,
and turns every user mistake into one line on stderr with exit code 2."""

from __future__ import annotations

import sqlite3
import struct
import xml.etree.ElementTree as ET
from pathlib import Path

import matplotlib.image
import numpy as np
import pytest
from matplotlib.colors import to_rgb

from host.cli import main
from host.journal import Journal, Note
from host.report.chart import OUTCOME_COLORS, STATE_COLORS, render
from host.report.source import load_timeline
from host.report.timeline import HealthState
from tests.report.journals import COMPONENTS, T0, device_shut_down, power_up

PNG_SIGNATURE = b"\x89PNG\r\n\x1a\n"


def _png_size(path: Path) -> tuple[int, int]:
    data = path.read_bytes()
    assert data[:8] == PNG_SIGNATURE and data[12:16] == b"IHDR"
    width, height = struct.unpack(">II", data[16:24])
    return int(width), int(height)


def _close(pixel: np.ndarray, color: str) -> bool:
    return bool(np.abs(pixel[:3] - np.array(to_rgb(color))).max() < 0.02)


def test_png_has_the_abnormal_colour_exactly_where_the_journal_says(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    journal = device_shut_down(tmp_path / "d.sqlite")
    out = tmp_path / "d.png"
    assert main(["report", str(journal), "-o", str(out)]) == 0
    assert "wrote" in capsys.readouterr().out
    width, height = _png_size(out)
    assert width == 1500 and 800 < height < 2000  # 10 in at 150 dpi; rows make the height
    # the layout of the same drawing tells where each row and each second lies
    layout = render(load_timeline(journal), tmp_path / "again.png")
    assert (layout.width_px, layout.height_px) == (width, height)
    img = matplotlib.image.imread(out)
    assert img.shape[:2] == (height, width)

    def pixel(component: str, t: float) -> np.ndarray:
        return img[round(layout.row_y_px[component]), round(layout.x_px(t))]

    abnormal, normal = STATE_COLORS[HealthState.ABNORMAL], STATE_COLORS[HealthState.NORMAL]
    assert _close(pixel("jaguar", 11.0), abnormal)  # off from 10.2 s to 12.2 s
    assert _close(pixel("jaguar", 5.0), normal)
    assert _close(pixel("jaguar", 14.0), normal)
    assert _close(pixel("jaguar_node", 14.0), abnormal)  # until 16.4 s
    assert _close(pixel("jaguar_node", 18.0), normal)
    assert _close(pixel("hokuyo", 11.0), normal)
    # the abnormal colour appears in exactly the two rows that were abnormal
    red = np.all(np.abs(img[:, :, :3] - np.array(to_rgb(abnormal))) < 0.02, axis=2)
    rows_with_red = {c for c, y in layout.row_y_px.items() if red[round(y)].any()}
    assert rows_with_red == {"jaguar", "jaguar_node"}
    # a bar of the succeeded-action colour is drawn along the top
    blue = np.all(np.abs(img[:, :, :3] - np.array(to_rgb(OUTCOME_COLORS["succeeded"]))) < 0.02,
                  axis=2)
    top_of_rows = min(layout.row_y_px.values())
    assert blue[: round(top_of_rows)].sum() > 200


def test_failed_actions_are_drawn_in_their_own_colour(tmp_path: Path) -> None:
    out = tmp_path / "f.png"
    assert main(["report", str(power_up(tmp_path / "f.sqlite", failing=True)), "-o",
                 str(out)]) == 0
    img = matplotlib.image.imread(out)
    for outcome in ("failed", "timeout"):
        hit = np.all(np.abs(img[:, :, :3] - np.array(to_rgb(OUTCOME_COLORS[outcome]))) < 0.03,
                     axis=2)
        assert hit.sum() > 50, outcome


def test_svg_is_xml_naming_every_component_and_action(tmp_path: Path) -> None:
    out = tmp_path / "p.svg"
    assert main(["report", str(power_up(tmp_path / "p.sqlite")), "-o", str(out),
                 "--model", "models/tedusar", "--title", "Power-up"]) == 0
    root = ET.parse(out).getroot()
    assert root.tag.endswith("svg")
    text = out.read_text()
    for name in (*COMPONENTS, "rviz", "HARDWARE", "DRIVERS", "NODES", "Power-up",
                 "power_up(laser_alignment)", "all normal at 38.3 s"):
        assert f"<!-- {name}" in text or name in text, name


def test_a_window_by_id_and_seconds_renders(tmp_path: Path) -> None:
    out = tmp_path / "w.png"
    assert main(["report", str(power_up(tmp_path / "p.sqlite")), "-o", str(out),
                 "--from", "5", "--to", "#60"]) == 0
    assert _png_size(out)[0] == 1500


@pytest.mark.parametrize(("make", "args", "message"), [
    ("power", ["-o", "{tmp}/x.jpg"], "cannot write .jpg (end the file name in .png or .svg)"),
    ("power", ["-o", "{tmp}/x"], "cannot write a file without a suffix"),
    ("power", ["-o", "{tmp}/nodir/x.png"], "does not exist"),
    ("missing", ["-o", "{tmp}/x.png"], "no such file"),
    ("notes", ["-o", "{tmp}/x.png"], "has no diagnoses"),
    ("empty", ["-o", "{tmp}/x.png"], "is empty"),
    ("garbage", ["-o", "{tmp}/x.png"], "is not a dxboard journal"),
    ("power", ["-o", "{tmp}/x.png", "--from", "ten"], "--from 'ten'"),
    ("power", ["-o", "{tmp}/x.png", "--from", "30", "--to", "20"], "is empty"),
    ("power", ["-o", "{tmp}/x.png", "--from", "#9999"], "no journal entry at or after id 9999"),
    ("power", ["-o", "{tmp}/x.png", "--model", "{tmp}"], "system.yaml"),
])
def test_mistakes_are_one_line_and_exit_2(tmp_path: Path, capsys: pytest.CaptureFixture[str],
                                          make: str, args: list[str], message: str) -> None:
    path = tmp_path / "j.sqlite"
    if make == "power":
        power_up(path)
    elif make == "notes":
        with Journal(path) as j:
            j.record(Note("only notes"), wall=T0, mono=0.0)
    elif make == "empty":
        Journal(path).close()
    elif make == "garbage":
        path.write_bytes(b"not sqlite at all, " * 100)
    argv = ["report", str(path), *(a.format(tmp=tmp_path) for a in args)]
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert err.startswith("dxboard report: error: ") and err.count("\n") == 1, err
    assert message in err
    assert not list(tmp_path.glob("x.*"))


def test_an_unreadable_sqlite_file_of_another_program_is_refused(
        tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    path = tmp_path / "other.sqlite"
    conn = sqlite3.connect(path)
    conn.execute("CREATE TABLE t (x)")
    conn.close()
    assert main(["report", str(path), "-o", str(tmp_path / "x.png")]) == 2
    assert "another program" in capsys.readouterr().err
